//! `cagerig animate`: samples skeleton and cage animations at given times and writes the
//! structures at each time.

use std::time::Instant;

use anyhow::bail;
use cagerig::skinning::SkinningMethod;

use crate::animation_args::{AnimationSourceArgs, NO_ANIMATION};
use crate::output_dir::{StagedDir, StateOutputArgs};
use crate::rig_source::{
    GENERATED_CAGE_FILE, RigInputArgs, report_generated_cage, write_generated_cage,
};
use crate::session_args::{SessionArgs, kind_parser, start_session};
use crate::state_files::write_state;

/// Checks the sample times: finite, each once (the files are named after the time).
pub fn check_times(times: &[f64]) -> anyhow::Result<()> {
    for (i, &t) in times.iter().enumerate() {
        if !cagerig::error::is_input_value(t) {
            bail!(
                "--times: value {} is {}; expected a finite time in seconds of magnitude at most 1e12",
                i + 1,
                cagerig::error::number_text(t)
            );
        }
        if let Some(j) = times[..i].iter().position(|&u| u == t) {
            bail!(
                "--times: {t} is given twice (values {} and {}); each sample time names its \
                 files (t{t}_*), so give each time once",
                j + 1,
                i + 1
            );
        }
    }
    Ok(())
}

/// `cagerig animate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub input: RigInputArgs,
    #[command(flatten)]
    pub animation: AnimationSourceArgs,
    /// Comma-separated sample times in seconds, each once (negative times allowed).
    #[arg(
        long,
        value_delimiter = ',',
        required = true,
        allow_hyphen_values = true
    )]
    pub times: Vec<f64>,
    #[command(flatten)]
    pub output: StateOutputArgs,
    /// Skinning method.
    #[arg(long, value_parser = kind_parser::<SkinningMethod>())]
    pub skinning: Option<SkinningMethod>,
    #[command(flatten)]
    pub session: SessionArgs,
    /// Print a JSON report on stdout: per sample time, the frame's time and how well the current
    /// cage follows the body (spread, deviation, flipped; see docs/method.md).
    #[arg(long)]
    pub json: bool,
}

/// One sample of `animate --json`.
#[derive(serde::Serialize)]
struct SampleReport {
    time: f64,
    frame_ms: f64,
    /// Whether C' is not CageUp's fit (a Green pose kept under `--unfitted-cage keep`).
    unfitted: bool,
    #[serde(flatten)]
    cage: cagerig::cage_quality::CageQuality,
}

/// `animate --json`.
#[derive(serde::Serialize)]
struct AnimateReport {
    cage_fit: cagerig::CageFitKind,
    coords: cagerig::CoordsKind,
    samples: Vec<SampleReport>,
    /// How many samples left C' unfitted.
    unfitted_samples: usize,
    /// The worst of each measure over the samples.
    worst: Option<cagerig::cage_quality::CageQuality>,
}

pub fn run(args: &Args) -> anyhow::Result<()> {
    let out = args.output.out.as_path();
    let times = args.times.as_slice();
    let (force, render, skinning, session_args) = (
        args.output.force,
        args.output.render,
        args.skinning,
        &args.session,
    );
    if !args.animation.is_given() {
        bail!("{NO_ANIMATION}");
    }
    check_times(times)?;
    let mut pictures = crate::pictures::PictureMaker::for_steps(render)?;
    let mut staged = StagedDir::create(out, force, crate::output_dir::OUT)?;
    let mut loaded = args.input.load_for_session()?;
    if let Some(g) = &loaded.generated_cage {
        report_generated_cage(&loaded.name, g, &out.join(GENERATED_CAGE_FILE));
        write_generated_cage(&mut staged, &g.cage)?;
    }
    let tracks = args.animation.tracks(&mut loaded)?;
    tracks.warn_times_past_end(times);
    let mut options = session_args.options();
    options.skinning = crate::session_args::choose_skinning(skinning, None, &loaded);
    let (session, warnings) = start_session(loaded, options)?;
    for w in &warnings {
        crate::errors::report_warning(w);
    }
    let mut player = tracks.resolve(&session)?.player(&session)?;
    let mut session = session;
    let probe = cagerig::cage_quality::CageQualityProbe::of_session(&session)?;
    let mut report = AnimateReport {
        cage_fit: session.cage_fit(),
        coords: session.coords_kind(),
        samples: Vec::with_capacity(times.len()),
        unfitted_samples: 0,
        worst: None,
    };
    for &t in times {
        let start = Instant::now();
        player
            .apply(t, &mut session)
            .map_err(|e| crate::session_args::event_error(format!("sample t = {t}"), e))?;
        let frame_ms = start.elapsed().as_secs_f64() * 1e3;
        let cage = probe.measure_session(&session);
        eprintln!("t = {t}: frame in {frame_ms:.3} ms; current cage: {cage}");
        report.worst = Some(report.worst.map_or(cage, |w| w.worst(cage)));
        let unfitted = session.posed_cage_unfitted().is_some();
        report.unfitted_samples += usize::from(unfitted);
        report.samples.push(SampleReport {
            time: t,
            frame_ms,
            unfitted,
            cage,
        });
        write_state(&mut staged, &format!("t{t}"), &session)?;
        if let Some(p) = &mut pictures {
            p.caption = Some(format!("t = {t} s"));
            p.write_staged(&session, &mut staged, &format!("t{t}.png"))?;
        }
    }
    let n = staged.finish()?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        println!("{n} files written to {}", out.display());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn duplicate_and_non_finite_times_are_refused() {
        assert!(check_times(&[0.75, -5.0, 4.0]).is_ok());
        let e = check_times(&[1.0, 1.0]).unwrap_err().to_string();
        assert!(e.contains("twice") && e.contains("values 1 and 2"), "{e}");
        assert!(check_times(&[f64::NAN]).is_err());
        assert!(check_times(&[1e300]).is_err());
    }
}
