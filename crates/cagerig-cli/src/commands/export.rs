//! `cagerig export RIG [--script EDITS.json] --out FILE.glb|FILE.gltf`: the (edited) character as a
//! standard rigged glTF binary — the rest mesh and skeleton after cage edits as the bind shape,
//! Ω as JOINTS_n/WEIGHTS_n, the current pose as the joint nodes' transforms.
//!
//! With `--skeleton-anim A --cage-anim B` or `--animation NAME` (glTF/FBX) `[--fps F]`: the
//! hybrid animation, sampled at F samples/s plus every key time, as node TRS animation and cage
//! keys as morph targets (see `cagerig_formats::gltf::export_animation`).
//!
//! glTF skins with LBS only: under `--skinning dqs|cor` a viewer shows the LBS result of the rig
//! (said in a warning) unless `--bake` adds one morph target per sample that turns it into
//! cagerig's DQS/CoR M' at the sample (`cagerig_formats::gltf::export_bake`).

use std::path::{Path, PathBuf};

use anyhow::bail;
use cagerig::session::RigSession;
use cagerig::skinning::SkinningMethod;
use cagerig_formats::gltf::export_animation;
use cagerig_formats::gltf::export_bake::BakeReport;

use crate::animation_args::AnimationSourceArgs;
use crate::rig_source::{RigInputArgs, note_generated_cage};
use crate::session_args::{SessionArgs, kind_parser};

#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub input: RigInputArgs,
    /// Edit script replayed before exporting (as for `edit`).
    #[arg(long)]
    pub script: Option<PathBuf>,
    /// Output: `.glb` (binary glTF) or `.gltf` (JSON, with its buffer `<stem>-<hash>.bin`
    /// written beside it); replaced atomically.
    #[arg(long)]
    pub out: PathBuf,
    /// The animation to export (none: the rig at its pose after the script).
    #[command(flatten)]
    pub animation: AnimationSourceArgs,
    /// Samples per second of the exported animation (key times are always samples).
    #[arg(long, default_value_t = 30.0)]
    pub fps: f64,
    /// Between two samples a viewer interpolates the joint nodes (lerp / slerp): samples are
    /// added where that departs from cagerig's M' by more than this fraction of the rest
    /// bounding-box diagonal (checked at the midpoint of every interval); 0 turns it off.
    #[arg(long, default_value_t = 1e-5)]
    pub max_between: f64,
    /// The most samples the refinement of `--max-between` may reach.
    #[arg(long, default_value_t = 100_000)]
    pub max_samples: usize,
    /// Skinning method (default: the script's, else the file's, else LBS). glTF viewers skin
    /// with LBS: under DQS/CoR they show the LBS result unless `--bake`.
    #[arg(long, value_parser = kind_parser::<SkinningMethod>())]
    pub skinning: Option<SkinningMethod>,
    /// With an animation under DQS/CoR: write cagerig's posed skin at every sample as a morph
    /// target (12 bytes per vertex and sample; weight 1 at its sample, LINEAR), so that viewers
    /// show the DQS/CoR result at the samples. Under LBS there is nothing to bake (a note says so).
    #[arg(long)]
    pub bake: bool,
    #[command(flatten)]
    pub session: SessionArgs,
}

pub fn run(args: &Args) -> anyhow::Result<()> {
    let writable = cagerig_formats::CharacterFormat::of(&args.out).is_some_and(|f| f.can_export());
    if !writable {
        bail!(
            "{}: export writes glTF 2.0: give an --out path ending in .glb (binary) or .gltf \
             (JSON with a .bin beside it)",
            args.out.display()
        );
    }
    let script = args
        .script
        .as_deref()
        .map(crate::commands::edit::read_script)
        .transpose()?;
    if !(args.fps.is_finite() && args.fps > 0.0 && args.fps <= 1000.0) {
        bail!("--fps {} must be in (0, 1000]", args.fps);
    }
    if !(args.max_between.is_finite() && (0.0..1.0).contains(&args.max_between)) {
        bail!(
            "--max-between {} must be a fraction of the diagonal in [0, 1) (0: no refinement)",
            args.max_between
        );
    }
    let mut loaded = args.input.load_for_session()?;
    note_generated_cage(&loaded);
    let tracks = args.animation.tracks(&mut loaded)?;
    let name = loaded
        .name
        .rsplit(['/', '\\'])
        .next()
        .and_then(|f| f.split('.').next())
        .unwrap_or("cagerig")
        .to_string();
    let animated = args.animation.is_given();
    if args.bake && !animated {
        bail!(
            "--bake writes the posed skin at the samples of an animation: give --animation, \
             --skeleton-anim or --cage-anim (for one pose, a one-key --skeleton-anim)"
        );
    }
    let mut options = args.session.options();
    options.allow_mesh_outside_cage = loaded.allow_outside_cage;
    options.skinning = crate::session_args::choose_skinning(
        args.skinning,
        script.as_ref().and_then(|s| s.skinning),
        &loaded,
    );
    let (mut session, warnings) = crate::session_args::start_session(loaded, options)?;
    for w in &warnings {
        crate::errors::report_warning(w);
    }
    if let (Some(script), Some(path)) = (&script, &args.script) {
        crate::session_args::replay_script(script, path, &mut session)?;
    }
    let method = session.skinning();
    let bake = args.bake && !method.is_linear();
    match (method, args.bake) {
        (SkinningMethod::Lbs, true) => eprintln!(
            "note: --bake under LBS: viewers skin with LBS as cagerig does, nothing to bake (no \
             target added)"
        ),
        (SkinningMethod::Lbs, false)
        | (
            SkinningMethod::Dqs
            | SkinningMethod::Cor
            | SkinningMethod::Blended
            | SkinningMethod::External,
            true,
        ) => {}
        (
            SkinningMethod::Dqs
            | SkinningMethod::Cor
            | SkinningMethod::Blended
            | SkinningMethod::External,
            false,
        ) => eprintln!(
            "warning: glTF skins with LBS: viewers show the LBS result of this rig, not \
             cagerig's {label} skin (up to a few % of the diagonal apart){hint}",
            label = method.label(),
            hint = if animated {
                "; --bake writes the {label} result as morph targets"
                    .replace("{label}", method.label())
            } else {
                String::new()
            }
        ),
    }
    let tracks = tracks.resolve(&session)?;
    if tracks.skeleton.is_none() && tracks.cage.is_none() {
        return export(&session, &args.out, &name);
    }
    // The animation keeps its source's name (the file's animation, else the animation file's
    // stem), not the character's.
    let animation_name = tracks.name.clone().unwrap_or_else(|| name.clone());
    let t = std::time::Instant::now();
    let keys: Vec<f64> = tracks
        .skeleton
        .iter()
        .flat_map(|s| s.times())
        .chain(tracks.cage.iter().flat_map(|c| c.times()))
        .copied()
        .collect();
    // The cage keys become the morph targets.
    let cage_track = tracks.cage.clone();
    let mut player = tracks.player(&session)?;
    let mut times = export_animation::sample_times(player.duration(), args.fps, &keys);
    let mut refinement = String::new();
    if args.max_between > 0.0 {
        let (lo, hi) = cagerig::mesh::bounding_box(session.rest_mesh());
        let diagonal = (hi - lo).length();
        // 10 % of the bound left for the f32 rounding of the file (measured against an
        // independent viewer in `gltf_export_resampling.rs`).
        let refined = cagerig_formats::gltf::export_resampling::refine_sample_times(
            &mut session,
            &mut player,
            &times,
            0.9 * args.max_between * diagonal,
            args.max_samples.max(times.len()),
            bake,
        )
        .map_err(|e| crate::session_args::event_error("refining the samples", e))?;
        refinement = format!(
            " ({} added so that a viewer{} stays within {:.1e} of the diagonal between samples, \
             {:.1e} at the worst midpoint)",
            refined.added,
            match (method.is_linear(), bake) {
                (true, _) => "",
                (false, true) => " of the baked skin",
                (false, false) => "'s LBS of the rig",
            },
            args.max_between,
            refined.largest_checked / diagonal.max(f64::MIN_POSITIVE)
        );
        if refined.capped {
            eprintln!(
                "warning: --max-samples {} reached: between some samples a viewer departs from \
                 cagerig by up to {:.1e} of the diagonal (raise --max-samples or --fps)",
                args.max_samples,
                refined.largest_checked / diagonal.max(f64::MIN_POSITIVE)
            );
        }
        times = refined.times;
    }
    let (document, bin, report) = export_animation::animation_to_gltf(
        &mut session,
        &mut player,
        cage_track.as_ref(),
        &times,
        &name,
        &animation_name,
        bake,
    )
    .map_err(|e| crate::session_args::event_error("exporting the animation", e))?;
    cagerig_formats::gltf::export::write_gltf_or_glb(&args.out, &document, &bin)?;
    println!(
        "{} written: {} samples{refinement} over {:.3} s in {:.1} ms",
        args.out.display(),
        times.len(),
        player.duration(),
        t.elapsed().as_secs_f64() * 1e3
    );
    if bake {
        report_bake(
            &session,
            &report,
            cage_track.as_ref().map_or(0, |c| c.times().len()),
        );
    }
    Ok(())
}

/// Says what `--bake` wrote and how close a viewer is to cagerig's M' at the samples.
fn report_bake(session: &RigSession, report: &BakeReport, cage_keys: usize) {
    let (lo, hi) = cagerig::mesh::bounding_box(session.rest_mesh());
    let diagonal = (hi - lo).length().max(f64::MIN_POSITIVE);
    let bytes =
        export_animation::baked_bytes(session.num_vertices(), cage_keys, report.samples) as f64;
    let label = session.skinning().label();
    println!(
        "baked {label}: {} morph targets ({:.2} MB: 12 B × {} vertices per sample, and their \
         weights); at the samples a viewer shows cagerig's {label} skin to {:.1e} of the \
         diagonal (the LBS alone was {:.1e} off); between samples it blends the two samples' \
         corrections linearly",
        report.samples,
        bytes / 1e6,
        session.num_vertices(),
        report.worst_residual / diagonal,
        report.largest_correction / diagonal
    );
    if report.singular > 0 {
        eprintln!(
            "warning: --bake: at {} vertex-samples the blended LBS matrix is singular (its \
             rotations cancel); their targets are least-squares solutions",
            report.singular
        );
    }
    if report.worst_residual > 1e-5 * diagonal {
        eprintln!(
            "warning: --bake: a viewer is up to {:.1e} of the diagonal from cagerig's {label} skin \
             at some sample",
            report.worst_residual / diagonal
        );
    }
}

fn export(session: &RigSession, out: &Path, name: &str) -> anyhow::Result<()> {
    let t = std::time::Instant::now();
    cagerig_formats::export_character(session, out, name)?;
    println!(
        "{} written ({} vertices, {} joints) in {:.1} ms",
        out.display(),
        session.rest_mesh().len(),
        session.skeleton().len(),
        t.elapsed().as_secs_f64() * 1e3
    );
    Ok(())
}
