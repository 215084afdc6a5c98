//! `cagerig render`: pictures of a rig, after an edit script or at animation times. One
//! picture is one PNG file at `--out`, replaced atomically; several (`--times` with more than
//! one time, `--turntable`) are one output folder at `--out` that appears complete, only after
//! every picture was drawn ([`StagedDir`]).

use std::path::{Path, PathBuf};

use anyhow::bail;
use cagerig::session::{DisplayPrecision, RigSession};
use cagerig::skinning::SkinningMethod;
use cagerig_render::CameraPreset;
use cagerig_render::rig_scene::{ColorBy, Layers};
use glam::DVec3;

use crate::animation_args::{AnimationSourceArgs, NO_ANIMATION};
use crate::output_dir::{OUT, StagedDir};
use crate::pictures::{CameraChoice, PictureMaker, PictureOptions, ViewArg};
use crate::rig_source::{RigInputArgs, note_generated_cage};
use crate::session_args::{SessionArgs, start_session};

#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub input: RigInputArgs,
    /// Edit script (the JSON of `cagerig edit`) applied before rendering; the picture shows
    /// the state after its last step.
    #[arg(long, conflicts_with_all = ["skeleton_anim", "cage_anim", "animation"])]
    pub script: Option<PathBuf>,
    /// The animation sampled at `--times`.
    #[command(flatten)]
    pub animation: AnimationSourceArgs,
    /// Comma-separated sample times in seconds (one picture each: OUT/t<time>.png when more
    /// than one).
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    pub times: Vec<f64>,
    /// Output PNG file; for several pictures (--times with more than one time, --turntable)
    /// an output folder, which appears complete, only after every picture was drawn.
    #[arg(long)]
    pub out: PathBuf,
    /// Replace a non-empty --out folder that holds an earlier run's output.
    #[arg(long)]
    pub force: bool,
    /// Pose(s) shown: current (M', C', S'), rest (M, C, S), or both side by side (rest left).
    #[arg(long, value_enum, default_value_t = ViewArg::Current)]
    pub view: ViewArg,
    /// Picture size in pixels, WIDTHxHEIGHT (both views together for --view both).
    #[arg(long, default_value = "1280x720")]
    pub size: String,
    /// Camera preset framing everything shown: front, side, top, three-quarter.
    #[arg(long, default_value = "three-quarter", conflicts_with_all = ["eye", "target"])]
    pub camera: String,
    /// Camera position x,y,z (world space; with --target).
    #[arg(long, requires = "target", allow_negative_numbers = true)]
    pub eye: Option<String>,
    /// Point looked at x,y,z (world space; with --eye).
    #[arg(long, requires = "eye", allow_negative_numbers = true)]
    pub target: Option<String>,
    /// Layers drawn, comma-separated from mesh, wireframe, cage, skeleton, flat, ground.
    #[arg(long, default_value = "mesh,cage,skeleton,ground")]
    pub show: String,
    /// Colour map on the skin: joint:NAME|INDEX (skin weights Ω), cage-vertex:K (mean value
    /// coordinates Φ, diverging), or on the cage handles: psi:NAME|INDEX (joint coordinates Ψ),
    /// cage-reach (each handle's distance from the skin over the rest cage's largest: red from
    /// 2.5, the usual colour up to 1).
    #[arg(long)]
    pub color_by: Option<String>,
    /// Leave out the pose labels.
    #[arg(long)]
    pub no_labels: bool,
    /// Write N pictures around the model (OUT/frame_000.png …) and an animated PNG of them
    /// (OUT/turntable.png); with several --times, OUT/t<time>_frame_000.png … per time.
    #[arg(long)]
    pub turntable: Option<u32>,
    /// Skinning method.
    #[arg(long, value_parser = crate::session_args::kind_parser::<cagerig::skinning::SkinningMethod>())]
    pub skinning: Option<SkinningMethod>,
    /// Draw the current skin from the f32 display path (LBS/DQS/CoR in f32, within 2e-6 of the
    /// bounding-box diagonal of the exact skin; faster on large characters). Cage, skeleton and
    /// rest pose are the exact ones either way.
    #[arg(long)]
    pub display_f32: bool,
    #[command(flatten)]
    pub session: SessionArgs,
}

/// Parses `WIDTHxHEIGHT`.
pub fn parse_size(text: &str) -> anyhow::Result<(u32, u32)> {
    let parse = || -> Option<(u32, u32)> {
        let (w, h) = text.split_once(['x', 'X'])?;
        Some((w.trim().parse().ok()?, h.trim().parse().ok()?))
    };
    match parse() {
        Some((w, h)) if (1..=16384).contains(&w) && (1..=16384).contains(&h) => Ok((w, h)),
        _ => {
            bail!("--size {text:?}: expected WIDTHxHEIGHT with each side 1 … 16384, e.g. 1280x720")
        }
    }
}

fn parse_point(option: &str, text: &str) -> anyhow::Result<DVec3> {
    let values: Vec<f64> = text
        .split(',')
        .map(|s| s.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| anyhow::anyhow!("{option} {text:?}: expected three numbers x,y,z"))?;
    match values.as_slice() {
        [x, y, z] if values.iter().all(|v| v.is_finite()) => Ok(DVec3::new(*x, *y, *z)),
        _ => bail!("{option} {text:?}: expected three finite numbers x,y,z"),
    }
}

/// Parses `--show`.
pub fn parse_layers(text: &str) -> anyhow::Result<Layers> {
    let mut layers = Layers {
        mesh: false,
        wireframe: false,
        cage: false,
        skeleton: false,
        flat: false,
        ground: false,
    };
    for name in text.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        match name {
            "mesh" => layers.mesh = true,
            "wireframe" => layers.wireframe = true,
            "cage" => layers.cage = true,
            "skeleton" => layers.skeleton = true,
            "flat" => layers.flat = true,
            "ground" => layers.ground = true,
            other => bail!(
                "--show: unknown layer {other:?}; expected some of mesh, wireframe, cage, skeleton, flat, ground"
            ),
        }
    }
    if layers.wireframe || layers.flat {
        layers.mesh = true;
    }
    if !(layers.mesh || layers.cage || layers.skeleton) {
        bail!(
            "--show {text:?} draws nothing: give at least one of mesh, wireframe, cage, skeleton"
        );
    }
    Ok(layers)
}

fn parse_joint(session: &RigSession, text: &str) -> anyhow::Result<usize> {
    let count = session.skeleton().len();
    if let Some(j) = session.skeleton().find(text) {
        return Ok(j);
    }
    match text.parse::<usize>() {
        Ok(j) if j < count => Ok(j),
        Ok(j) => bail!(
            "--color-by: joint {j} does not exist (the rig has {count} joints, 0 … {})",
            count.saturating_sub(1)
        ),
        Err(_) => {
            let names: Vec<&str> = session
                .skeleton()
                .joints()
                .iter()
                .map(|j| j.name.as_str())
                .collect();
            bail!(
                "--color-by: no joint named {text:?}; the joints are {}",
                names.join(", ")
            )
        }
    }
}

/// Parses `--color-by` against the rig.
pub fn parse_color_by(session: &RigSession, text: &str) -> anyhow::Result<ColorBy> {
    if text == "cage-reach" {
        return Ok(ColorBy::CageReach);
    }
    let Some((kind, value)) = text.split_once(':') else {
        bail!("--color-by {text:?}: expected joint:NAME, cage-vertex:K, psi:NAME or cage-reach");
    };
    let color_by = match kind {
        "joint" => ColorBy::JointWeights(parse_joint(session, value)?),
        "psi" => ColorBy::JointCageCoords(parse_joint(session, value)?),
        "cage-vertex" => ColorBy::CageCoords(value.parse().map_err(|_| {
            anyhow::anyhow!("--color-by {text:?}: expected a cage vertex index after cage-vertex:")
        })?),
        _ => {
            bail!("--color-by {text:?}: expected joint:NAME, cage-vertex:K, psi:NAME or cage-reach")
        }
    };
    color_by
        .validate(session)
        .map_err(|e| anyhow::anyhow!("--color-by {text:?}: {e}"))?;
    Ok(color_by)
}

/// Where the pictures go: one file, or the output folder of several.
enum Pictures {
    File(PathBuf),
    Folder(StagedDir),
}

/// The output of `args`: a folder when it asks for several pictures (refusing a `.png` name,
/// which was the file prefix of older versions), else the file `--out`, with `.png` added when
/// its name does not end in it (said on stderr; the path printed at the end is the one written).
fn open_pictures(args: &Args) -> anyhow::Result<Pictures> {
    let is_png = args
        .out
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    let several = match (args.times.len(), args.turntable) {
        (n, _) if n > 1 => format!("--times with {n} times"),
        (_, Some(_)) => "--turntable".to_owned(),
        _ if is_png => return Ok(Pictures::File(args.out.clone())),
        _ => {
            let Some(file_name) = args.out.file_name() else {
                bail!(
                    "--out {}: expected the name of a PNG file, e.g. picture.png",
                    args.out.display()
                );
            };
            let mut file_name = file_name.to_os_string();
            file_name.push(".png");
            let path = args.out.with_file_name(file_name);
            eprintln!(
                "note: --out {} does not end in .png: the picture is written to {}",
                args.out.display(),
                path.display()
            );
            return Ok(Pictures::File(path));
        }
    };
    if is_png {
        bail!(
            "--out {}: {several} writes a folder of pictures; expected a folder name, e.g. {}",
            args.out.display(),
            args.out.with_extension("").display()
        );
    }
    Ok(Pictures::Folder(StagedDir::create(
        &args.out, args.force, OUT,
    )?))
}

pub fn run(args: &Args) -> anyhow::Result<()> {
    let size = parse_size(&args.size)?;
    let layers = parse_layers(&args.show)?;
    let camera = match (&args.eye, &args.target) {
        (Some(eye), Some(target)) => CameraChoice::LookAt {
            eye: parse_point("--eye", eye)?,
            target: parse_point("--target", target)?,
        },
        _ => CameraChoice::Preset(CameraPreset::from_name(&args.camera).ok_or_else(|| {
            anyhow::anyhow!(
                "--camera {:?}: expected one of front, side, top, three-quarter",
                args.camera
            )
        })?),
    };
    if let Some(t) = args.times.iter().find(|t| !t.is_finite()) {
        bail!("--times: sample time {t} is not finite");
    }
    if args.turntable == Some(0) {
        bail!("--turntable 0: expected at least one frame");
    }
    match (args.times.is_empty(), args.animation.is_given()) {
        (false, false) => bail!("--times samples an animation: {NO_ANIMATION}"),
        (true, true) => bail!(
            "--skeleton-anim, --animation and --cage-anim are sampled at --times: give the times \
             to draw (e.g. --times 0,0.5)"
        ),
        (true, false) | (false, true) => {}
    }
    let script = args
        .script
        .as_deref()
        .map(crate::commands::edit::read_script)
        .transpose()?;
    let mut pictures = open_pictures(args)?;
    let mut loaded = args.input.load_for_session()?;
    note_generated_cage(&loaded);
    let tracks = args.animation.tracks(&mut loaded)?;
    tracks.warn_times_past_end(&args.times);
    let mut options = args.session.options();
    options.skinning = crate::session_args::choose_skinning(
        args.skinning,
        script.as_ref().and_then(|s| s.skinning),
        &loaded,
    );
    let (mut session, warnings) = start_session(loaded, options)?;
    for w in &warnings {
        crate::errors::report_warning(w);
    }
    if args.display_f32 {
        session.set_display_precision(DisplayPrecision::F32)?;
    }
    let color_by = match &args.color_by {
        Some(text) => parse_color_by(&session, text)?,
        None => ColorBy::None,
    };
    if let Some(script) = &script {
        let path = args.script.as_deref().unwrap_or(Path::new(""));
        crate::session_args::replay_script(script, path, &mut session)?;
    }
    let mut maker = PictureMaker::new(PictureOptions {
        view: args.view,
        size,
        camera,
        layers,
        color_by,
        labels: !args.no_labels,
    })?;
    // The cage vertices the script moved are marked.
    if let Some(script) = &script {
        maker.marked = crate::pictures::MarkedHandles::of_steps(&script.steps);
    }
    if args.times.is_empty() {
        render_state(&mut maker, &session, args, "", &mut pictures)?;
    } else {
        let mut player = tracks.resolve(&session)?.player(&session)?;
        for &t in &args.times {
            player
                .apply(t, &mut session)
                .map_err(|e| crate::session_args::event_error(format!("sample t = {t}"), e))?;
            crate::session_args::warn_if_unfitted(&format!("the picture at t = {t}"), &session);
            maker.caption = Some(format!("t = {t} s"));
            let name = if args.times.len() == 1 {
                String::new()
            } else {
                format!("t{t}")
            };
            render_state(&mut maker, &session, args, &name, &mut pictures)?;
        }
    }
    eprintln!("rendered on {}", maker.adapter_name());
    let written = match pictures {
        Pictures::File(path) => vec![path],
        Pictures::Folder(staged) => {
            let names = staged.names().to_vec();
            staged.finish()?;
            names.iter().map(|n| args.out.join(n)).collect()
        }
    };
    for path in &written {
        println!("{}", path.display());
    }
    Ok(())
}

/// The pictures of one state: one picture (the file, or `<name>.png` in the folder) or a
/// turntable (`<name>_frame_000.png` … and the animated `<name>_turntable.png`, without the
/// `<name>_` when `name` is empty).
fn render_state(
    maker: &mut PictureMaker,
    session: &RigSession,
    args: &Args,
    name: &str,
    pictures: &mut Pictures,
) -> anyhow::Result<()> {
    let staged = match pictures {
        Pictures::File(path) => return maker.write(session, path),
        Pictures::Folder(staged) => staged,
    };
    let Some(frames) = args.turntable else {
        return maker.write_staged(session, staged, &format!("{name}.png"));
    };
    let prefix = if name.is_empty() {
        String::new()
    } else {
        format!("{name}_")
    };
    let mut images = Vec::with_capacity(frames as usize);
    for k in 0..frames {
        let yaw = std::f64::consts::TAU * k as f64 / frames as f64;
        let camera = maker.camera(session, yaw);
        let image = maker.picture(session, &camera)?;
        let png = image.to_png()?;
        staged.write(&format!("{prefix}frame_{k:03}.png"), &|w| w.write_all(&png))?;
        images.push(image);
    }
    staged.write_into(|dir| -> anyhow::Result<()> {
        let path = dir.join(format!("{prefix}turntable.png"));
        Ok(cagerig_render::image::write_apng(&path, &images, 80)?)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_layers_and_suffixes_parse() {
        assert_eq!(parse_size("640x480").unwrap(), (640, 480));
        assert!(parse_size("0x480").is_err());
        assert!(
            parse_size("640")
                .unwrap_err()
                .to_string()
                .contains("WIDTHxHEIGHT")
        );
        let layers = parse_layers("wireframe,skeleton").unwrap();
        assert!(layers.mesh && layers.wireframe && layers.skeleton && !layers.cage);
        assert!(
            parse_layers("mesh,bogus")
                .unwrap_err()
                .to_string()
                .contains("bogus")
        );
        assert!(parse_layers("ground").is_err());
        assert!(parse_point("--eye", "1,2").is_err());
        assert_eq!(
            parse_point("--eye", "1,-2,3").unwrap(),
            DVec3::new(1.0, -2.0, 3.0)
        );
    }
}
