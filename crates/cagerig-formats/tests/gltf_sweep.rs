//! Every skinned glTF file the repository holds, imported and animated as a viewer shows it.
//!
//! The sweep finds each `.gltf`/`.glb` under `data/` whose JSON has a skin, imports it with the
//! default options, and compares cagerig's posed skin with the independent evaluation of the
//! file (tests/common: the `gltf` crate's readers and Σ w G IBM v) at rest and at several times
//! of every animation, to 1e-5 of the bounding-box diagonal.
//!
//! Point it at a library of your own characters with `CAGERIG_GLTF_SWEEP=dir1:dir2` (searched
//! recursively): files the repository cannot redistribute, such as the Khronos sample BrainStem
//! (© Smith Micro Software, Poser EULA), are swept from there.
//! `cargo test -p cagerig-formats --test gltf_sweep -- --nocapture` prints one line per file.

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod common;

use std::path::{Path, PathBuf};

use cagerig::animation::SkeletonTrack;
use cagerig::playback::{AnimationPlayer, PoseChannels};
use cagerig::session::{RigParts, RigSession, SessionOptions};
use cagerig_formats::{ImportOptions, import_character};
use common::{ReferenceGltf, box_cage, data};
use glam::{DAffine3, DVec3};

/// The skinned samples the repository holds (under `data/`); the sweep fails when one is missing.
const SAMPLES: [&str; 5] = [
    "fox/Fox.glb",
    "gltf/CesiumMan/CesiumMan.glb",
    "gltf/RiggedFigure/RiggedFigure.gltf",
    "gltf/RiggedSimple/RiggedSimple.glb",
    "gltf/SimpleSkin/SimpleSkin.gltf",
];

/// The bar: a viewer and cagerig agree to 1e-5 of the diagonal.
const TOLERANCE: f64 = 1e-5;

fn diagonal(p: &[DVec3]) -> f64 {
    let (lo, hi) = cagerig::mesh::bounding_box(p);
    (hi - lo).length()
}

/// Every `.gltf`/`.glb` below `dir`, sorted.
fn gltf_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut paths: Vec<PathBuf> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
    paths.sort();
    for p in paths {
        if p.is_dir() {
            gltf_files(&p, out);
        } else if matches!(p.extension().and_then(|e| e.to_str()), Some("gltf" | "glb")) {
            out.push(p);
        }
    }
}

/// Whether the file's JSON declares at least one skin.
fn has_skin(path: &Path) -> bool {
    let bytes = std::fs::read(path).unwrap();
    gltf::Gltf::from_slice_without_validation(&bytes)
        .map(|g| g.skins().next().is_some())
        .unwrap_or(false)
}

/// What one file gave: the largest distance, over the node pose and the sampled animation
/// times, between cagerig's posed skin and the reference viewer's (relative to the diagonal),
/// the number of poses compared, and how it was posed.
struct Sweep {
    worst: f64,
    poses: usize,
    how: String,
}

/// cagerig's posed skin M' for a track at a time: through a rig session (box cage) when one
/// can be built, else by the skeleton alone (track locals → FK → T = posed · rest⁻¹ → LBS of M),
/// which is the session's M' before any cage edit. A flat character (SimpleSkin's strip) has a
/// rank-deficient Φ for every cage and is posed the second way.
enum Poser {
    Session(Box<RigSession>),
    Skeleton(cagerig::skinning::lbs::LinearBlendSkinning),
}

fn worst_error(path: &Path) -> Result<Sweep, String> {
    let c = import_character(path, &ImportOptions::default()).map_err(|e| e.to_string())?;
    let reference = ReferenceGltf::load(path);
    let diag = diagonal(&c.mesh.positions);
    let parts = RigParts::new(
        c.mesh.clone(),
        c.skeleton.clone(),
        c.skin_weights.clone(),
        box_cage(&c.mesh.positions, 0.05),
    );
    let (mut poser, mut how) = match RigSession::new(parts, SessionOptions::default()) {
        Ok((session, _)) => (Poser::Session(Box::new(session)), "session".to_owned()),
        Err(e) => (
            Poser::Skeleton(cagerig::skinning::lbs::LinearBlendSkinning::new(
                &c.skin_weights,
            )),
            format!("skeleton only ({e})"),
        ),
    };
    // Vertices without any weight: the file leaves them undefined (the glTF validator calls
    // such a file invalid; viewers differ: three.js collapses them to the origin, Blender keeps
    // them at rest). cagerig keeps them at rest with a warning; they are compared with M.
    let unweighted: Vec<bool> = (0..c.mesh.num_vertices())
        .map(|v| c.skin_weights.row(v).0.is_empty())
        .collect();
    let num_unweighted = unweighted.iter().filter(|&&u| u).count();
    if num_unweighted > 0 {
        how.push_str(&format!(
            ", {num_unweighted} unweighted vertices kept at rest"
        ));
    }
    let mut worst = 0.0f64;
    let mut poses = 0;
    // Without an animation a viewer shows the file's own node transforms (the bind pose when the
    // file is saved in it): M' of the node pose, played as a one-key track.
    let node_pose =
        SkeletonTrack::new(vec![0.0], vec![c.node_pose.clone()]).map_err(|e| e.to_string())?;
    let mut tracks = vec![(None, node_pose, vec![0.0])];
    for (a, animation) in c.animations.iter().enumerate() {
        let keys = animation.track.times();
        let d = animation.duration;
        let mut times = vec![0.0, 0.37 * d, 0.81 * d, d];
        // Keys and the midpoints between the first few keys (where interpolation shows).
        for w in keys.windows(2).take(4) {
            times.push(w[1]);
            times.push(0.5 * (w[0] + w[1]));
        }
        tracks.push((Some(a), animation.track.clone(), times));
    }
    let nj = c.skeleton.len();
    let rest_frames = c.skeleton.rest_world_from_joint();
    let mut posed = vec![DVec3::ZERO; c.mesh.num_vertices()];
    for (animation, track, times) in tracks {
        let mut player = match &poser {
            Poser::Session(session) => Some(
                AnimationPlayer::with_channels(
                    session,
                    Some(track.clone()),
                    None,
                    PoseChannels::Full,
                )
                .map_err(|e| e.to_string())?,
            ),
            Poser::Skeleton(_) => None,
        };
        for t in times {
            match (&mut poser, &mut player) {
                (Poser::Session(session), Some(player)) => {
                    player.apply(t, session).map_err(|e| e.to_string())?;
                    posed.copy_from_slice(session.posed_mesh());
                }
                (Poser::Skeleton(lbs), _) => {
                    let mut locals = vec![DAffine3::IDENTITY; nj];
                    track.sample(t, &mut locals);
                    let mut world = vec![DAffine3::IDENTITY; nj];
                    c.skeleton.forward_kinematics(&locals, &mut world);
                    let mut transforms = vec![DAffine3::IDENTITY; nj];
                    cagerig::Skeleton::skinning_transforms(&rest_frames, &world, &mut transforms);
                    lbs.apply(&transforms, &c.mesh.positions, &mut posed);
                }
                (Poser::Session(_), None) => unreachable!("a session always has a player"),
            }
            let expect = reference.skin(animation, t);
            for (v, ((p, e), &u)) in posed.iter().zip(&expect).zip(&unweighted).enumerate() {
                let target = if u { c.mesh.positions[v] } else { *e };
                let err = p.distance(target) / diag;
                // NaN sticks (f64::max would drop it).
                if err.is_nan() || err > worst {
                    worst = err;
                }
            }
            poses += 1;
        }
    }
    Ok(Sweep { worst, poses, how })
}

#[test]
fn every_skinned_gltf_file_animates_as_a_viewer_shows_it() {
    let mut roots = vec![data("")];
    if let Ok(extra) = std::env::var("CAGERIG_GLTF_SWEEP") {
        roots.extend(std::env::split_paths(&extra));
    }
    let mut files = Vec::new();
    for root in &roots {
        gltf_files(root, &mut files);
    }
    files.retain(|p| has_skin(p));
    for sample in SAMPLES {
        assert!(
            files.iter().any(|p| p.ends_with(sample)),
            "the repository's skinned sample {sample} was not found among {files:?}"
        );
    }
    let mut failures = Vec::new();
    for path in &files {
        match worst_error(path) {
            Ok(Sweep { worst, poses, how }) => {
                println!("{worst:9.2e}  {poses:4} poses  {}  ({how})", path.display());
                if worst.is_nan() || worst > TOLERANCE {
                    failures.push(format!("{}: {worst:e} of the diagonal", path.display()));
                }
            }
            Err(e) => {
                println!("  failed               {}: {e}", path.display());
                failures.push(format!("{}: {e}", path.display()));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} files differ from the viewer by more than {TOLERANCE:e} of the diagonal or \
         fail:\n{}",
        failures.len(),
        files.len(),
        failures.join("\n")
    );
}
