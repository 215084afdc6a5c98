//! `cagerig-studio`: the interactive editor.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::bail;
use cagerig_studio::benchmark_drag::DragBenchmark;
use cagerig_studio::rig_open::RigSource;
use cagerig_studio::{StartupOptions, StudioApp};
use clap::Parser;

/// cagerig studio: pose a character with its skeleton and sculpt it with its cage, in the rest
/// pose or the current pose, with every structure kept in sync.
#[derive(Debug, Parser)]
#[command(name = "cagerig-studio", version, after_help = AFTER_HELP)]
struct Args {
    /// A character (OBJ with its companion files, .glb, .gltf, .fbx) or a .cagerig session.
    /// Without it, the built-in demo rig opens.
    path: Option<PathBuf>,
    /// The cage (OBJ) of the character, instead of the discovered or embedded one.
    #[arg(long, requires = "path")]
    cage: Option<PathBuf>,
    /// glTF/FBX: the skin to import, by name or index (default: the first), as `cagerig --skin`.
    #[arg(long, requires = "path")]
    skin: Option<String>,
    /// When the character has no cage, generate one (as `cagerig cage`). A character with no
    /// cage opens with a generated one anyway, and the log says so; this flag goes with
    /// --cage-vertices.
    #[arg(long, requires = "path")]
    auto_cage: bool,
    /// Vertex count of a generated cage (lowered on a small mesh to what the rig can use).
    #[arg(long, default_value_t = 100, requires = "auto_cage")]
    cage_vertices: usize,
    /// A built-in demo rig instead of a file (bar, bar_irregular, snake).
    #[arg(long, conflicts_with = "path")]
    builtin: Option<String>,
    /// Resolution of the built-in rig (bar: ring intervals; snake: about the vertex count).
    #[arg(long, requires = "builtin")]
    resolution: Option<usize>,
    /// A .cagerig session file to open.
    #[arg(long, conflicts_with_all = ["path", "builtin"])]
    session: Option<PathBuf>,
    /// An edit script (the JSON of `cagerig edit`) applied through the editor before the first
    /// frame, one undo step per step.
    #[arg(long)]
    script: Option<PathBuf>,
    /// Save the session to this file (after --script).
    #[arg(long)]
    save_session: Option<PathBuf>,
    /// Write a PNG of the window after the first frames, then quit.
    #[arg(long)]
    screenshot: Option<PathBuf>,
    /// Window size, WIDTHxHEIGHT in points.
    #[arg(long, default_value = "1600x900", value_parser = parse_size)]
    size: (f32, f32),
    /// Quit after this many frames.
    #[arg(long)]
    quit_after_frames: Option<u64>,
    /// Write per-frame timings (median and max of sync, normals/upload, UI, frame time) as JSON.
    #[arg(long)]
    frame_stats: Option<PathBuf>,
    /// Select these cage vertices at start (comma-separated indices).
    #[arg(long, value_delimiter = ',')]
    select_cage: Vec<usize>,
    /// Select this joint at start (index).
    #[arg(long)]
    select_joint: Option<usize>,
    /// Colour map at start: weights (Ω of the selected joint), cage-coords (Φ of the first
    /// selected cage vertex), joint-coords (Ψ of the selected joint).
    #[arg(long, value_enum, default_value = "none")]
    color_map: cagerig_studio::view_state::ColorMode,
    /// Bind with these cage coordinates after opening: mvc (the paper's) or green
    /// (shape-preserving cage edits); switchable later in the Rig panel.
    #[arg(long, value_parser = parse_coords)]
    coords: Option<cagerig::CoordsKind>,
    /// Simulate a drag (one event per frame) to measure interactive frame times.
    #[arg(long, value_enum)]
    benchmark_drag: Option<DragBenchmark>,
}

const AFTER_HELP: &str = "\
Without a display (a server, CI), run it under a virtual one with a screen larger than the
window (--size, default 1600x900; xvfb-run's own screen is 1280x1024):
  xvfb-run -a -s \"-screen 0 1920x1080x24\" cagerig-studio --script edits.json --screenshot out.png
For pictures without any window, use `cagerig render` or `cagerig demo`.
Shortcuts: Help ▸ Shortcuts in the editor.";

fn parse_size(text: &str) -> Result<(f32, f32), String> {
    let (w, h) = text
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WIDTHxHEIGHT (e.g. 1600x900), found {text:?}"))?;
    let parse = |s: &str| {
        s.trim()
            .parse::<f32>()
            .ok()
            .filter(|v| v.is_finite() && (64.0..=16384.0).contains(v))
            .ok_or_else(|| {
                format!(
                    "expected WIDTHxHEIGHT with sizes 64 to 16384 (e.g. 1600x900), found {text:?}"
                )
            })
    };
    Ok((parse(w)?, parse(h)?))
}

/// Whether a display server is reachable (Linux / BSD: X11 or Wayland).
fn display_available() -> bool {
    if cfg!(any(target_os = "windows", target_os = "macos")) {
        return true;
    }
    let set = |name: &str| std::env::var_os(name).is_some_and(|v| !v.is_empty());
    set("DISPLAY") || set("WAYLAND_DISPLAY")
}

/// `--coords`: a name of `CoordsKind::ALL`, through its `FromStr`.
fn parse_coords(text: &str) -> Result<cagerig::CoordsKind, String> {
    text.parse()
        .map_err(|e: cagerig::coords_kind::UnknownCoordsKind| e.to_string())
}

fn run(args: Args) -> anyhow::Result<()> {
    if !display_available() {
        bail!(
            "no display: neither DISPLAY nor WAYLAND_DISPLAY is set, so no window can open.\n\
             Run it under a virtual display: xvfb-run -a cagerig-studio [ARGS]\n\
             (for pictures without any window: `cagerig render` or `cagerig demo`)"
        );
    }
    let (source, session) = match (&args.path, &args.builtin, &args.session) {
        (_, _, Some(s)) => (None, Some(s.clone())),
        (Some(p), _, None)
            if p.extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("cagerig")) =>
        {
            (None, Some(p.clone()))
        }
        (Some(p), _, None) => (
            Some(RigSource::File {
                path: p.clone(),
                cage: args.cage.clone(),
                skin: args.skin.clone(),
                auto_cage: args.auto_cage.then_some(args.cage_vertices),
            }),
            None,
        ),
        (None, Some(name), None) => (
            Some(RigSource::Builtin {
                name: name.clone(),
                resolution: args.resolution,
            }),
            None,
        ),
        (None, None, None) => (None, None),
    };
    let options = StartupOptions {
        source,
        session,
        script: args.script,
        save_session: args.save_session,
        screenshot: args.screenshot,
        quit_after_frames: args.quit_after_frames,
        frame_stats: args.frame_stats,
        state_dir: None,
        drag_benchmark: args.benchmark_drag,
        failures: Default::default(),
        select_cage: args.select_cage,
        select_joint: args.select_joint,
        color_mode: args.color_map,
        coords: args.coords,
        page_files: None,
        weights_offload: None,
    };
    let failures = std::sync::Arc::clone(&options.failures);
    let native = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_inner_size(egui::vec2(args.size.0, args.size.1))
            .with_title("cagerig studio")
            .with_drag_and_drop(true),
        renderer: eframe::Renderer::Wgpu,
        ..Default::default()
    };
    eframe::run_native(
        "cagerig studio",
        native,
        Box::new(move |cc| Ok(Box::new(StudioApp::new(cc, options)))),
    )
    .map_err(|e| {
        anyhow::anyhow!(
            "could not start the window: {e}\n(without a GPU, install a software Vulkan driver: \
             mesa-vulkan-drivers; without a display, run under xvfb-run -a)"
        )
    })?;
    let failures = failures.lock().map(|f| f.len()).unwrap_or_default();
    if failures > 0 {
        // Each was written to stderr when it was logged.
        return Err(ErrorsPrinted(failures).into());
    }
    Ok(())
}

/// The run logged errors, each already written to stderr: the exit status says so, and the
/// messages are not printed a second time.
#[derive(Debug)]
struct ErrorsPrinted(usize);

impl std::fmt::Display for ErrorsPrinted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} error(s), printed above", self.0)
    }
}

impl std::error::Error for ErrorsPrinted {}

fn main() -> ExitCode {
    let args = Args::parse();
    match run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.is::<ErrorsPrinted>() => ExitCode::from(2),
        Err(e) => {
            eprintln!("cagerig-studio: {e:#}");
            ExitCode::from(2)
        }
    }
}
