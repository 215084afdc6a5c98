//! `cagerig demo`: a hybrid edit on a built-in rig (bend with the skeleton, inflate with the rest
//! cage, grab the current cage), its states and pictures, and each sync's time.

use std::path::PathBuf;
use std::time::Instant;

use cagerig::session::RigSession;
use glam::DVec3;

use crate::output_dir::StagedDir;
use crate::rig_source::{CageCheck, RigArgs, load_rig_or_generate_cage};
use crate::session_args::{SessionArgs, event_error, start_session};
use crate::state_files::write_state;

/// Pictures of the demo's steps, kept in memory until the run succeeded; `None` when pictures
/// are off or no graphics adapter exists (then the run goes on without them and says why).
struct DemoPictures {
    maker: Option<crate::pictures::PictureMaker>,
    images: Vec<(String, cagerig_render::RgbaImage)>,
    /// The current pose after each step, for `sequence.png`.
    sequence: Option<cagerig_render::RgbaImage>,
}

impl DemoPictures {
    fn new(enabled: bool) -> Self {
        let maker = enabled.then(|| crate::pictures::PictureMaker::new(Default::default()));
        let maker = match maker {
            Some(Ok(maker)) => Some(maker),
            Some(Err(e)) => {
                println!("warning: no pictures: {e:#}");
                None
            }
            None => None,
        };
        Self {
            maker,
            images: Vec::new(),
            sequence: None,
        }
    }

    /// The pictures of one step: `name`.png (rest | current) and the step's panel of the strip,
    /// both captioned with `caption` (what the step did).
    fn add(&mut self, name: &str, caption: &str, session: &RigSession) -> anyhow::Result<()> {
        if let Some(maker) = &mut self.maker {
            maker.caption = Some(caption.to_owned());
            let camera = maker.camera(session, 0.0);
            let image = maker.picture(session, &camera)?;
            self.images.push((format!("{name}.png"), image));
            // The current pose alone, appended to the sequence strip.
            let both = maker.options;
            maker.options.view = crate::pictures::ViewArg::Current;
            maker.options.size = (560, 560);
            let camera = maker.camera(session, 0.0);
            let current = maker.picture(session, &camera);
            maker.options = both;
            let current = current?;
            self.sequence = Some(match self.sequence.take() {
                Some(strip) => cagerig_render::RgbaImage::side_by_side(&strip, &current, 4),
                None => current,
            });
        }
        Ok(())
    }

    /// Puts the pictures into the staged output; returns the names written.
    fn write_staged(&self, staged: &mut StagedDir) -> anyhow::Result<Vec<String>> {
        let mut names = Vec::new();
        let strip = self
            .sequence
            .iter()
            .map(|s| ("sequence.png".to_string(), s));
        for (name, image) in self.images.iter().map(|(n, i)| (n.clone(), i)).chain(strip) {
            let png = image
                .to_png()
                .map_err(|e| anyhow::anyhow!("encoding {name}: {e}"))?;
            staged.write(&name, &|w| w.write_all(&png))?;
            names.push(name);
        }
        Ok(names)
    }
}

/// `cagerig demo`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Built-in rig to use.
    #[arg(long, default_value = "bar")]
    pub builtin: String,
    /// Mesh resolution parameter of the built-in rig.
    #[arg(long)]
    pub resolution: Option<usize>,
    /// Output directory.
    #[arg(long, default_value = "cagerig-demo")]
    pub out: PathBuf,
    /// Do not render the PNG picture of each step (rest and current pose side by side).
    #[arg(long)]
    pub no_pictures: bool,
    #[command(flatten)]
    pub session: SessionArgs,
}

pub fn run(args: &Args) -> anyhow::Result<()> {
    let (builtin, resolution, out, pictures, session_args) = (
        args.builtin.as_str(),
        args.resolution,
        args.out.as_path(),
        !args.no_pictures,
        &args.session,
    );
    let args = RigArgs {
        mesh: None,
        cage: None,
        builtin: Some(builtin.to_string()),
        resolution,
        skin: None,
        allow_outside_cage: false,
        weights: None,
        skeleton: None,
        auto_weights: false,
    };
    let t = Instant::now();
    // The session validates the cage (start_session), so the loader does not.
    let loaded = load_rig_or_generate_cage(&args, true, false, None, CageCheck::Session)?;
    let (mut s, warnings) = start_session(loaded, session_args.options())?;
    println!(
        "loaded built-in rig {builtin:?}: {} vertices, {} joints, {} cage vertices, {} coordinates ({:.1} ms incl. coordinates, MaxVol, Ψ)",
        s.rest_mesh().len(),
        s.skeleton().len(),
        s.rest_cage().len(),
        s.coords_kind().label(),
        t.elapsed().as_secs_f64() * 1e3
    );
    for w in &warnings {
        println!("{}: {w}", w.label());
    }
    // The output folder is complete or absent: files go to a staging folder renamed to `out`
    // at the end; an earlier demo's output there is replaced (the demo writes only its own
    // state files and pictures, and a folder holding anything else is refused).
    let mut staged = StagedDir::create(out, true, crate::output_dir::OUT)?;
    let mut pictures = DemoPictures::new(pictures);
    write_state(&mut staged, "0_loaded", &s)?;
    pictures.add("0_loaded", "0. as loaded", &s)?;
    let (lo, hi) = cagerig::mesh::bounding_box(s.rest_cage());
    let centre = (lo + hi) * 0.5;
    let size = (hi - lo).length();

    // 1. Bend with the skeleton: rotate the middle joint.
    let joint = s.skeleton().len() / 2;
    let t = Instant::now();
    s.rotate_joint(joint, DVec3::Z, 60f64.to_radians())
        .map_err(|e| event_error("1. skeleton edit", e))?;
    println!(
        "1. skeleton edit: joint {joint} ({}) +60° about Z → M', C' synced in {:.3} ms",
        s.skeleton().joint(joint).name,
        t.elapsed().as_secs_f64() * 1e3
    );
    write_state(&mut staged, "1_bend", &s)?;
    pictures.add("1_bend", &format!("1. bend: joint {joint} +60\u{b0}"), &s)?;

    // 2. Inflate with the rest cage: push the cage vertices on the far half outwards.
    let (verts, offsets): (Vec<usize>, Vec<DVec3>) = s
        .rest_cage()
        .iter()
        .enumerate()
        .filter(|(_, c)| c.x > centre.x)
        .map(|(k, c)| {
            let mut radial = *c - centre;
            radial.x = 0.0;
            (k, radial.normalize_or_zero() * 0.08 * size)
        })
        .unzip();
    let t = Instant::now();
    s.move_rest_cage(&verts, &offsets)
        .map_err(|e| event_error("2. rest-cage edit", e))?;
    println!(
        "2. rest-cage edit: inflated {} cage vertices → M, S, S', M', C' synced in {:.3} ms",
        verts.len(),
        t.elapsed().as_secs_f64() * 1e3
    );
    write_state(&mut staged, "2_inflate", &s)?;
    pictures.add("2_inflate", "2. inflate the rest cage", &s)?;

    // 3. Grab the current cage: pull the vertex farthest along +X.
    let far = s
        .posed_cage()
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.x.total_cmp(&b.1.x))
        .map(|(k, _)| k)
        .unwrap_or(0);
    let target = s.posed_cage()[far] + DVec3::new(0.0, 0.1 * size, 0.0);
    let t = Instant::now();
    s.move_posed_cage(&[far], &[DVec3::new(0.0, 0.1 * size, 0.0)])
        .map_err(|e| event_error("3. current-cage grab", e))?;
    println!(
        "3. current-cage grab: vertex {far} → C (CageRev refactor + solve), full loop synced in {:.3} ms; landed {:.2e} from target",
        t.elapsed().as_secs_f64() * 1e3,
        s.posed_cage()[far].distance(target)
    );
    write_state(&mut staged, "3_grab", &s)?;
    pictures.add("3_grab", "3. grab the current cage", &s)?;
    let picture_names = pictures.write_staged(&mut staged)?;
    let n = staged.finish()?;
    println!("{n} files written to {}", out.display());
    for name in picture_names {
        let what = if name == "sequence.png" {
            "current pose after each step, left to right"
        } else {
            "rest pose left, current pose right"
        };
        println!("picture ({what}): {}", out.join(name).display());
    }
    Ok(())
}
