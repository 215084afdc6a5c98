//! The web page's side of the studio: starting it on the page's canvas, the page's files
//! ([`cagerig_studio::page_files::PageFiles`], implemented by `window.cagerigPage` in
//! `web/index.html`), and the exports the page and its test call.
//!
//! Every export works on the one running studio; before [`start`] has finished, or after a
//! panic, they report that no studio runs. The exports the page's worker calls
//! ([`generated_cage`], [`automatic_weights`]) need no studio.

use std::cell::{Cell, RefCell};
use std::collections::HashMap;
use std::sync::Arc;

use cagerig_studio::StudioApp;
use cagerig_studio::offload::{
    WeightsInput, WeightsOffload, WeightsOutput, WeightsReply, stage_code, stage_of_code,
};
use cagerig_studio::page_files::PageFiles;
use cagerig_studio::rig_open::RigSource;
use cagerig_studio::startup::StartupOptions;
use wasm_bindgen::prelude::*;

use crate::rig_state::RigState;

/// The samples the page serves beside itself (`web/build.sh` copies them to `samples/`).
const SAMPLES: [&str; 3] = ["Arm.glb", "Fox.glb", "CesiumMan.glb"];

#[wasm_bindgen]
extern "C" {
    /// `window.cagerigPage.chooseCharacter()`: clicks the page's file input.
    #[wasm_bindgen(js_namespace = cagerigPage, js_name = chooseCharacter)]
    fn page_choose_character();
    /// `window.cagerigPage.fetchSample(name)`: fetches `samples/<name>` and opens it.
    #[wasm_bindgen(js_namespace = cagerigPage, js_name = fetchSample)]
    fn page_fetch_sample(name: &str);
    /// `window.cagerigPage.download(name, mime, bytes)`: offers a download.
    #[wasm_bindgen(catch, js_namespace = cagerigPage, js_name = download)]
    fn page_download(name: &str, mime: &str, bytes: &[u8]) -> Result<(), JsValue>;
    /// `window.cagerigPage.openBytes(name, bytes)`: opens a character file the page holds,
    /// through the page's worker (which generates its cage when it has none).
    #[wasm_bindgen(js_namespace = cagerigPage, js_name = openBytes)]
    fn page_open_bytes(name: &str, bytes: &[u8]);
    /// `window.cagerigPage.computeWeights(id, input)`: hands a Bind's automatic weights
    /// (`input`: [`WeightsInput`] as JSON) to the page's worker, which answers through
    /// [`weights_progress`] and [`weights_finished`] with the same `id`.
    #[wasm_bindgen(js_namespace = cagerigPage, js_name = computeWeights)]
    fn page_compute_weights(id: u32, input: &str);
    /// `self.cagerigWorker.weightsProgress(stage, done, total)`, in the page's worker: relays
    /// the automatic weights' progress to the page.
    #[wasm_bindgen(js_namespace = cagerigWorker, js_name = weightsProgress)]
    fn worker_weights_progress(stage: u32, done: usize, total: usize);
}

/// [`PageFiles`] through `window.cagerigPage`.
#[derive(Debug)]
struct Page;

impl PageFiles for Page {
    fn choose_character(&self) {
        page_choose_character();
    }

    fn samples(&self) -> Vec<String> {
        SAMPLES.iter().map(|s| (*s).to_string()).collect()
    }

    fn fetch_sample(&self, name: &str) {
        page_fetch_sample(name);
    }

    fn open_dropped(&self, file: egui::DroppedFileHandle) {
        wasm_bindgen_futures::spawn_local(async move {
            let name = file.path().display().to_string();
            let read = file.bytes_async().await;
            // Runs between frames: the studio is free.
            let _ = match read {
                Ok(bytes) => {
                    page_open_bytes(&name, &bytes);
                    Ok(())
                }
                Err(e) => with_app(|app| {
                    app.diagnostics
                        .log
                        .error(format!("{name}: the browser could not read the file: {e}"))
                }),
            };
        });
    }

    fn download(&self, file_name: &str, mime: &str, bytes: &[u8]) -> Result<(), String> {
        page_download(file_name, mime, bytes).map_err(|e| format!("{e:?}"))
    }
}

/// [`WeightsOffload`] through the page's worker: each computation gets an id, and its reply
/// waits in [`WEIGHTS`] for the worker's answer.
#[derive(Debug)]
struct WorkerWeights;

impl WeightsOffload for WorkerWeights {
    fn start(&self, input: WeightsInput, reply: WeightsReply) {
        let json = match input.to_json() {
            Ok(json) => json,
            Err(e) => return reply.finish(Err(e.to_string())),
        };
        let id = NEXT_WEIGHTS.with(|n| {
            let id = n.get().wrapping_add(1);
            n.set(id);
            id
        });
        WEIGHTS.with(|w| w.borrow_mut().insert(id, reply));
        page_compute_weights(id, &json);
    }
}

thread_local! {
    /// The automatic weights the worker computes, by id.
    static WEIGHTS: RefCell<HashMap<u32, WeightsReply>> = RefCell::new(HashMap::new());
    /// The last id given to one.
    static NEXT_WEIGHTS: Cell<u32> = const { Cell::new(0) };
    /// The running studio.
    static RUNNER: RefCell<Option<eframe::WebRunner>> = const { RefCell::new(None) };
    /// Its egui context, to ask for a frame after a change from outside.
    static CONTEXT: RefCell<Option<egui::Context>> = const { RefCell::new(None) };
}

/// Runs `f` on the studio (and asks for a new frame), or fails when none runs.
fn with_app<T>(f: impl FnOnce(&mut StudioApp) -> T) -> Result<T, JsValue> {
    let result = RUNNER.with(|runner| {
        let runner = runner.borrow();
        let runner = runner
            .as_ref()
            .ok_or_else(|| JsValue::from_str("the studio has not started"))?;
        let mut app = runner
            .app_mut::<StudioApp>()
            .ok_or_else(|| JsValue::from_str("the studio has stopped (see the console)"))?;
        Ok::<T, JsValue>(f(&mut app))
    })?;
    repaint();
    Ok(result)
}

/// Starts the studio on the canvas with id `canvas_id`, on the built-in snake.
#[wasm_bindgen]
pub async fn start(canvas_id: String) -> Result<(), JsValue> {
    eframe::WebLogger::init(log::LevelFilter::Warn).ok();
    let document = web_sys::window()
        .and_then(|w| w.document())
        .ok_or_else(|| JsValue::from_str("no document"))?;
    let canvas = document
        .get_element_by_id(&canvas_id)
        .ok_or_else(|| JsValue::from_str(&format!("no element with id {canvas_id:?}")))?
        .dyn_into::<web_sys::HtmlCanvasElement>()?;
    let runner = eframe::WebRunner::new();
    let options = StartupOptions {
        // No file system: nothing is read from or written to a state folder.
        state_dir: Some("/cagerig-studio".into()),
        page_files: Some(Arc::new(Page)),
        weights_offload: Some(Arc::new(WorkerWeights)),
        ..StartupOptions::default()
    };
    runner
        .start(
            canvas,
            eframe::WebOptions::default(),
            Box::new(move |cc| {
                let ctx = cc.egui_ctx.clone();
                CONTEXT.with(|c| *c.borrow_mut() = Some(ctx));
                Ok(Box::new(StudioApp::new(cc, options)))
            }),
        )
        .await?;
    RUNNER.with(|r| *r.borrow_mut() = Some(runner));
    Ok(())
}

/// The largest character file the page opens (the wasm memory holds the file, the rig and its
/// dense coordinates; larger characters open in the native studio).
const LARGEST_FILE: usize = 64 << 20;

/// The size of the largest character file the page opens, in bytes.
#[wasm_bindgen]
pub fn largest_file_bytes() -> usize {
    LARGEST_FILE
}

/// The page's worker's part of opening a character file (`name` gives its format): the cage
/// that opening it generates, as JSON (`None` when the file brings its cage), computed in the
/// worker's own instance of this module so that the page's thread stays free. An error is the
/// message opening the file gives (the page hands it to [`report_open_error`]).
#[wasm_bindgen]
pub fn generated_cage(name: String, bytes: Vec<u8>) -> Result<Option<String>, JsValue> {
    let source = RigSource::Memory {
        path: name.into(),
        bytes: bytes.into(),
        auto_cage: None,
        generated_cage: None,
    };
    let generated = cagerig_studio::rig_open::generated_cage_of(&source)
        .map_err(|e| JsValue::from_str(&e.to_string()))?;
    generated
        .map(|cage| serde_json::to_string(&cage))
        .transpose()
        .map_err(|e| JsValue::from_str(&format!("the generated cage as JSON: {e}")))
}

/// Opens a character file the page read (file input, drop, sample): `name` gives its format,
/// `cage_json` is the worker's [`generated_cage`] for it (`None` when the file has its cage,
/// or to generate it here). A file over [`LARGEST_FILE`] is refused in the log.
#[wasm_bindgen]
pub fn open_file(name: String, bytes: Vec<u8>, cage_json: Option<String>) -> Result<(), JsValue> {
    let generated = cage_json
        .map(|json| serde_json::from_str(&json))
        .transpose()
        .map_err(|e| JsValue::from_str(&format!("{name}: the worker's cage: {e}")))?;
    with_app(|app| {
        if bytes.len() > LARGEST_FILE {
            app.diagnostics.log.error(format!(
                "cannot open: {name}: {:.1} MB is more than the web studio opens ({} MB); open \
                 it in the native studio",
                bytes.len() as f64 / 1048576.0,
                LARGEST_FILE >> 20
            ));
        } else {
            app.open_character_bytes(&name, bytes, generated);
        }
    })
}

/// The page's worker's part of a Bind: the automatic weights of `input` ([`WeightsInput`] as
/// JSON, from `window.cagerigPage.computeWeights`), as [`WeightsOutput`] JSON, computed in the
/// worker's own instance of this module with the same code as a bind on the page. Progress
/// goes to `self.cagerigWorker.weightsProgress`. An error is a message for the page's log.
#[wasm_bindgen]
pub fn automatic_weights(input: String) -> Result<String, JsValue> {
    let error = |e: cagerig_studio::offload::OffloadError| JsValue::from_str(&e.to_string());
    WeightsInput::from_json(&input)
        .and_then(|input| {
            input.compute(&|p| worker_weights_progress(stage_code(p.stage), p.done, p.total))
        })
        .and_then(|output| output.to_json())
        .map_err(error)
}

/// The worker's progress on the automatic weights of computation `id` (`stage` as
/// `stage_code` numbers it); unknown ids and stages are ignored.
#[wasm_bindgen]
pub fn weights_progress(id: u32, stage: u32, done: usize, total: usize) {
    let Some(stage) = stage_of_code(stage) else {
        return;
    };
    WEIGHTS.with(|w| {
        if let Some(reply) = w.borrow().get(&id) {
            reply.report(cagerig::auto_weights::Progress { stage, done, total });
        }
    });
    repaint();
}

/// The worker's answer for the automatic weights of computation `id`: `output` (the
/// [`automatic_weights`] JSON) or `error` (a message); the Bind goes on with it at the
/// studio's next frame, and an error goes to the log. Unknown ids are ignored.
#[wasm_bindgen]
pub fn weights_finished(id: u32, output: Option<String>, error: Option<String>) {
    let Some(reply) = WEIGHTS.with(|w| w.borrow_mut().remove(&id)) else {
        return;
    };
    let result = match (output, error) {
        (_, Some(error)) => Err(format!("automatic weights in the worker: {error}")),
        (Some(json), None) => WeightsOutput::from_json(&json).map_err(|e| e.to_string()),
        (None, None) => Err("the worker gave no automatic weights".into()),
    };
    reply.finish(result);
    repaint();
}

/// Asks the studio for a frame (it polls what came from outside).
fn repaint() {
    CONTEXT.with(|c| {
        if let Some(ctx) = c.borrow().as_ref() {
            ctx.request_repaint();
        }
    });
}

/// Binds the rig's skeleton with automatic weights, as the Skeleton panel's Bind does (the
/// weights in the page's worker, the rig then on the page's thread).
#[wasm_bindgen]
pub fn bind_automatic() -> Result<(), JsValue> {
    with_app(StudioApp::bind_automatic)
}

/// The rig's skinning weights Ω as JSON `{"joints": #J, "rows": [[[joint, weight], …], …]}`
/// (one row per vertex), for the test's comparison with native runs.
#[wasm_bindgen]
pub fn skin_weights() -> Result<String, JsValue> {
    with_app(|app| {
        app.project.doc.as_ref().map_or_else(
            || "null".to_string(),
            |doc| crate::rig_state::weights_json(doc.session.skin_weights()),
        )
    })
}

/// Logs why the page's worker could not open a character file, as the studio logs a file it
/// cannot open (the open rig stays).
#[wasm_bindgen]
pub fn report_open_error(message: String) -> Result<(), JsValue> {
    with_app(|app| app.diagnostics.log.error(format!("cannot open: {message}")))
}

/// Offers the rig as a `.glb` download (File ▸ Download glTF).
#[wasm_bindgen]
pub fn download_glb() -> Result<(), JsValue> {
    with_app(StudioApp::download_glb)
}

/// Opens a built-in rig (`snake`, `bar`, `bar_irregular`) at its default resolution.
#[wasm_bindgen]
pub fn open_builtin(name: String) -> Result<(), JsValue> {
    with_app(|app| {
        app.request_open(cagerig_studio::opening::OpenRequest::Rig(
            RigSource::Builtin {
                name,
                resolution: None,
            },
        ))
    })
}

/// The rig's state (S', C, C', M, M') as JSON, for the test's comparison with native runs.
#[wasm_bindgen]
pub fn rig_state() -> Result<String, JsValue> {
    with_app(|app| {
        app.project.doc.as_ref().map_or_else(
            || "null".to_string(),
            |doc| RigState::of(&doc.session).to_json(),
        )
    })
}

/// Runs an edit script (`cagerig edit`'s JSON) through the studio's command path, one undo
/// step per step; returns the milliseconds the engine took (`performance.now()`).
#[wasm_bindgen]
pub fn run_script(json: String) -> Result<f64, JsValue> {
    let script = cagerig::script::EditScript::parse(&json)
        .map_err(|e| JsValue::from_str(&format!("the script: {e}")))?;
    with_app(|app| {
        let doc = app
            .project
            .doc
            .as_mut()
            .ok_or_else(|| JsValue::from_str("no rig is open"))?;
        let started = web_time::Instant::now();
        doc.run_script(&script)
            .map_err(|e| JsValue::from_str(&e.to_string()))?;
        Ok(started.elapsed().as_secs_f64() * 1e3)
    })?
}

/// The studio's status as JSON: the rig's name and sizes, whether it is opening or binding, unsaved
/// edits, the undo depth, the frames drawn and the log.
#[wasm_bindgen]
pub fn status() -> Result<String, JsValue> {
    with_app(|app| {
        let doc = app.project.doc.as_ref();
        let log: Vec<serde_json::Value> = app
            .diagnostics
            .log
            .lines()
            .iter()
            .map(|l| serde_json::json!({"level": format!("{:?}", l.level), "text": l.text}))
            .collect();
        serde_json::json!({
            "name": doc.map(|d| d.source.display_name()),
            "vertices": doc.map(|d| d.session.num_vertices()),
            "joints": doc.map(|d| d.session.skeleton().len()),
            "cage_vertices": doc.map(|d| d.session.rest_cage().len()),
            "opening": app.is_opening(),
            "binding": doc.is_some_and(|d| d.bind_job().is_some()),
            "unsaved": app.unsaved(),
            "undo_depth": doc.map(|d| d.history().undo_len()),
            "frames": app.frames(),
            "selected_joint": app.tools.selection.joint,
            "selected_cage": app.tools.selection.cage.iter().collect::<Vec<_>>(),
            "log": log,
        })
        .to_string()
    })
}

/// Where a posed joint (`kind` "joint") or a current-cage vertex (`kind` "cage") of index
/// `index` is drawn in the current-pose view, in CSS pixels of the page; `None` when it is not
/// drawn.
#[wasm_bindgen]
pub fn screen_point(kind: String, index: usize) -> Result<Option<Vec<f64>>, JsValue> {
    with_app(|app| {
        let doc = app.project.doc.as_ref()?;
        let point = match kind.as_str() {
            "joint" => doc.session.posed_joints().nth(index)?,
            "cage" => *doc.session.posed_cage().get(index)?,
            _ => return None,
        };
        let view = cagerig_studio::view_state::CURRENT;
        let rect = app.tools.interaction.view_rects[view];
        let at = app.view.projection(view).project(point)?;
        Some(vec![
            f64::from(rect.min.x) + at.x,
            f64::from(rect.min.y) + at.y,
        ])
    })
}

/// Whether the studio has edits not yet downloaded as a session (the page asks before it is
/// closed).
#[wasm_bindgen]
pub fn has_unsaved_edits() -> bool {
    with_app(|app| app.unsaved()).unwrap_or(false)
}
