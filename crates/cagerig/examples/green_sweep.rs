//! The single-joint sweep of a Green rig of the Arm (`data/arm`, its hand-made cage): every
//! joint (or the joints given) about x, y and z to 15°, 30°, 45°, 60° and 90°, each angle from
//! the rest pose (one event) and as a continuation of the previous angle (one event each, the
//! pose kept between them). Prints the refused events per mode, the worst cage quality of the
//! accepted ones (`CageQualityProbe`) and the time.
//!
//! ```sh
//! cargo run --release -p cagerig --example green_sweep -- [fold-safe|lipman] [regularised|paper] [all|issue|J,J,…]
//! ```
//!
//! `issue`: joints 1, 3, 4, 5, 8, 12, 16, 20, 24 from the rest pose only.

use std::path::Path;
use std::time::Instant;

use cagerig::cage_quality::{CageQuality, CageQualityProbe};
use cagerig::coords::stretched_normals::FaceTermKind;
use cagerig::rig_files::load_rig_files;
use cagerig::session::{RigSession, SessionOptions};
use cagerig::{CageFitKind, CoordsKind, RigError};
use glam::DVec3;

const ANGLES: [f64; 5] = [15.0, 30.0, 45.0, 60.0, 90.0];

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let face_term = match args.first().map(String::as_str) {
        Some("lipman") => FaceTermKind::Lipman,
        _ => FaceTermKind::FoldSafe,
    };
    let cage_fit = match args.get(1).map(String::as_str) {
        Some("paper") => CageFitKind::Paper,
        _ => CageFitKind::Regularised,
    };
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/arm");
    let files = load_rig_files(&dir.join("arm.obj"), None)?;
    let options = SessionOptions {
        coords: CoordsKind::Green,
        green_face_term: face_term,
        cage_fit,
        ..SessionOptions::default()
    };
    let mut s = RigSession::new(files.parts, options)?.0;
    let nj = s.skeleton().len();
    let (joints, continuation): (Vec<usize>, bool) = match args.get(2).map(String::as_str) {
        Some("issue") => (vec![1, 3, 4, 5, 8, 12, 16, 20, 24], false),
        Some(list) if list != "all" => (
            list.split(',')
                .map(str::parse)
                .collect::<Result<Vec<usize>, _>>()?,
            true,
        ),
        _ => ((0..nj).collect(), true),
    };
    let probe = CageQualityProbe::of_session(&s)?;
    println!("{face_term:?}, {cage_fit:?}, joints {joints:?}");
    let start = Instant::now();
    let mut events = 0;
    let mut refused_rest = Vec::new();
    let mut refused_continued = Vec::new();
    let mut worst: Option<CageQuality> = None;
    let mut record =
        |s: &RigSession, result: Result<(), RigError>, refused: &mut Vec<String>, what: String| {
            match result {
                Ok(()) => {
                    let q = probe.measure_session(s);
                    worst = Some(worst.map_or(q, |w| w.worst(q)));
                }
                Err(RigError::GreenFitFailed(f)) => refused.push(format!("{what} ({f})")),
                Err(e) => return Err(e),
            }
            Ok(())
        };
    for &joint in &joints {
        for (axis_name, axis) in [("x", DVec3::X), ("y", DVec3::Y), ("z", DVec3::Z)] {
            for angle in ANGLES {
                s.reset_pose();
                let result = s.rotate_joint(joint, axis, angle.to_radians());
                events += 1;
                record(
                    &s,
                    result,
                    &mut refused_rest,
                    format!("joint {joint} {axis_name} {angle}° from rest"),
                )?;
            }
            if continuation {
                s.reset_pose();
                let mut at = 0.0;
                for angle in ANGLES {
                    let result = s.rotate_joint(joint, axis, (angle - at).to_radians());
                    events += 1;
                    if result.is_ok() {
                        at = angle;
                    }
                    record(
                        &s,
                        result,
                        &mut refused_continued,
                        format!("joint {joint} {axis_name} {angle}° continued"),
                    )?;
                }
            }
        }
    }
    s.reset_pose();
    let seconds = start.elapsed().as_secs_f64();
    for r in refused_rest.iter().chain(&refused_continued) {
        println!("refused: {r}");
    }
    println!(
        "{events} events: refused {} from rest, {} continued; worst accepted: {}; {seconds:.1} s",
        refused_rest.len(),
        refused_continued.len(),
        worst.map_or("none".to_string(), |q| q.to_string())
    );
    Ok(())
}
