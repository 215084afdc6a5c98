//! The Arm example of the paper tool, read through every reader.

// tests, benches and examples may panic on a broken fixture

use std::path::{Path, PathBuf};

use cagerig::Warning;
use cagerig::io::{self, SkeletonAnimationVersion};
use glam::{DAffine3, DVec3};

fn arm() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/arm"))
}

fn file(name: &str) -> PathBuf {
    arm().join(name)
}

#[test]
fn discovery_finds_the_arm_companions() {
    let d = io::discover(&file("arm.obj"), None);
    assert_eq!(d.cage, Some(file("arm_cage.obj")));
    assert_eq!(d.skeleton, Some(file("arm.skt")));
    assert_eq!(d.skin_weights, Some(file("arm.skw")));
    assert_eq!(d.cor_weights, Some(file("arm_corWeights.txt")));
    assert_eq!(d.cage_coords, Some(file("arm_cage_cageWeights.txt")));
    assert_eq!(d.maxvol, Some(file("arm_cage.maxvol")));
    assert_eq!(d.skeleton_animation, Some(file("arm_skelAnim.txt")));
    assert_eq!(d.cage_animation, Some(file("arm_cageAnim.txt")));
}

#[test]
fn arm_rig_loads_with_expected_sizes() {
    let mesh = io::read_obj(&file("arm.obj")).unwrap();
    assert_eq!((mesh.num_vertices(), mesh.num_triangles()), (2089, 4156));
    let cage = io::read_obj(&file("arm_cage.obj")).unwrap();
    assert_eq!((cage.num_vertices(), cage.num_triangles()), (58, 112));
    let skeleton = io::read_skt(&file("arm.skt")).unwrap();
    assert_eq!(skeleton.len(), 25);
    assert_eq!(skeleton.joint(0).name, "Skeleton");
    assert_eq!(skeleton.parent(0), None);
    assert_eq!(skeleton.parent(3), Some(2));
    assert_eq!(
        skeleton.joint(3).rest_world_from_joint,
        DAffine3::from_translation(DVec3::new(-35.220709, 118.921547, 1.563874))
    );

    let (omega, warnings) = io::read_skw(&file("arm.skw"), 2089, 25).unwrap();
    let renormalised = warnings
        .iter()
        .find_map(|w| match w {
            Warning::WeightsRenormalised { rows, worst_sum } => Some((*rows, *worst_sum)),
            _ => None,
        })
        .expect("arm.skw rows do not sum to 1 and must be reported");
    println!("arm.skw: {warnings:?}");
    assert!(renormalised.0 > 0);
    assert!((0.999..=1.00001).contains(&renormalised.1));
    assert!(omega.max_influences() <= 7);
    for v in 0..2089 {
        let s: f64 = omega.row(v).1.iter().sum();
        assert!((s - 1.0).abs() < 1e-12, "row {v} sums to {s}");
    }

    let phi = io::read_cage_weights(&file("arm_cage_cageWeights.txt"), 2089, 58).unwrap();
    assert_eq!((phi.num_vertices(), phi.num_cage_vertices()), (2089, 58));
    assert!(phi.max_partition_error() < 1e-4);
    // Φ·C reproduces M to the file's 6-decimal rounding.
    let mut m = vec![DVec3::ZERO; 2089];
    phi.apply(&cage.positions, &mut m);
    let err = cagerig::mesh::max_distance(&m, &mesh.positions);
    println!("max |Φ·C − M| = {err:e}");
    assert!(err < 1e-2);

    let cor = io::read_cor_weights(&file("arm_corWeights.txt"), 2089).unwrap();
    assert_eq!(cor.nrows(), 2089);
    let sums = cor.row_sums();
    assert!(sums.iter().all(|s| (s - 1.0).abs() < 1e-5));
    let per_row: Vec<usize> = (0..2089).map(|i| cor.row(i).0.len()).collect();
    assert_eq!(
        (per_row.iter().min(), per_row.iter().max()),
        (Some(&9), Some(&217))
    );

    let rows = io::read_maxvol(&file("arm_cage.maxvol"), 2089).unwrap();
    assert_eq!(rows.len(), 58);
    assert_eq!((rows[0], rows[57]), (13, 538));
}

#[test]
fn arm_animations_load() {
    let skeleton = io::read_skt(&file("arm.skt")).unwrap();
    let (track, version) =
        io::read_skeleton_animation(&file("arm_skelAnim.txt"), &skeleton).unwrap();
    assert_eq!(version, SkeletonAnimationVersion::V3GlobalFrames);
    assert_eq!(track.times(), &[0.0, 3.0, 6.5, 9.0, 10.0]);
    assert_eq!(track.num_joints(), 25);
    // FK of the locals reproduces the global frames of the file (keyframe 1, joint 5).
    let mut world = vec![DAffine3::IDENTITY; 25];
    skeleton.forward_kinematics(&track.keys()[1], &mut world);
    assert!(
        world[5]
            .translation
            .abs_diff_eq(DVec3::new(-37.725312, 115.949636, 28.029666), 1e-9)
    );

    let cage_track = io::read_cage_animation(&file("arm_cageAnim.txt"), 58).unwrap();
    assert_eq!(cage_track.times(), &[0.0, 1.5, 3.0]);
    assert_eq!(cage_track.num_cage_vertices(), 58);

    // Written back (V3, round-trip floats) and re-read: same locals.
    let text = io::skeleton_animation::skeleton_animation_text(
        &track,
        &skeleton,
        version,
        io::FloatFormat::RoundTrip,
    )
    .unwrap();
    let (back, _) =
        io::parse_skeleton_animation(text.as_bytes(), Path::new("mem"), &skeleton).unwrap();
    for (a, b) in back
        .keys()
        .iter()
        .flatten()
        .zip(track.keys().iter().flatten())
    {
        assert!(a.abs_diff_eq(*b, 1e-9));
    }
}

#[test]
fn reference_rest_mesh_equals_arm_obj() {
    let mesh = io::read_obj(&file("arm.obj")).unwrap();
    let reference = io::read_obj(&file("reference/s0_M_rest.obj")).unwrap();
    assert_eq!(reference.triangles, mesh.triangles);
    assert_eq!(reference.positions, mesh.positions);
    let cage = io::read_obj(&file("arm_cage.obj")).unwrap();
    let reference_cage = io::read_obj(&file("reference/s0_C_rest.obj")).unwrap();
    assert_eq!(reference_cage.positions, cage.positions);
}

#[test]
fn arm_writes_reload_identically() {
    let dir = std::env::temp_dir().join(format!("cagerig_io_arm_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mesh = io::read_obj(&file("arm.obj")).unwrap();
    io::write_obj(&dir.join("m.obj"), &mesh.positions, &mesh.triangles).unwrap();
    assert_eq!(io::read_obj(&dir.join("m.obj")).unwrap(), mesh);

    let skeleton = io::read_skt(&file("arm.skt")).unwrap();
    io::write_skt(&dir.join("s.skt"), &skeleton).unwrap();
    assert_eq!(io::read_skt(&dir.join("s.skt")).unwrap(), skeleton);

    let phi = io::read_cage_weights(&file("arm_cage_cageWeights.txt"), 2089, 58).unwrap();
    io::write_cage_weights(&dir.join("w.txt"), &phi, io::FloatFormat::RoundTrip).unwrap();
    assert_eq!(
        io::read_cage_weights(&dir.join("w.txt"), 2089, 58).unwrap(),
        phi
    );
    // The tool's 6-decimal format reproduces the shipped file byte for byte? It has the same
    // values (the shipped file was written with 6 decimals).
    io::write_cage_weights(&dir.join("w6.txt"), &phi, io::FloatFormat::TOOL).unwrap();
    assert_eq!(
        io::read_cage_weights(&dir.join("w6.txt"), 2089, 58).unwrap(),
        phi
    );

    let rows = io::read_maxvol(&file("arm_cage.maxvol"), 2089).unwrap();
    io::write_maxvol(&dir.join("m.maxvol"), &rows).unwrap();
    assert_eq!(io::read_maxvol(&dir.join("m.maxvol"), 2089).unwrap(), rows);
    std::fs::remove_dir_all(&dir).unwrap();
}
