//! Tests of [`AutoWeights`] on analytic cases.

use std::sync::Mutex;

use glam::{DAffine3, DVec3};
use proptest::prelude::*;

use super::*;
use crate::Joint;

/// A closed box `[lo, hi]` whose faces are split in `n` quads along x and 2 × 2 across, as a
/// welded mesh (outward).
fn bar(lo: DVec3, hi: DVec3, n: usize) -> TriMesh {
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    // Rings of 8 vertices around the x axis at n + 1 stations, plus the two end faces.
    let ring = |t: f64| -> Vec<DVec3> {
        let x = lo.x + (hi.x - lo.x) * t;
        let (y0, y1, z0, z1) = (lo.y, hi.y, lo.z, hi.z);
        let (ym, zm) = (0.5 * (y0 + y1), 0.5 * (z0 + z1));
        [
            (y0, z0),
            (ym, z0),
            (y1, z0),
            (y1, zm),
            (y1, z1),
            (ym, z1),
            (y0, z1),
            (y0, zm),
        ]
        .map(|(y, z)| DVec3::new(x, y, z))
        .to_vec()
    };
    for s in 0..=n {
        positions.extend(ring(s as f64 / n as f64));
    }
    for s in 0..n as u32 {
        for k in 0..8u32 {
            let (a, b) = (s * 8 + k, s * 8 + (k + 1) % 8);
            let (c, d) = (a + 8, b + 8);
            triangles.push([a, c, d]);
            triangles.push([a, d, b]);
        }
    }
    // End caps: a fan around each end's centre.
    for (station, flip) in [(0u32, false), (n as u32, true)] {
        let centre = positions.len() as u32;
        let x = if flip { hi.x } else { lo.x };
        positions.push(DVec3::new(x, 0.5 * (lo.y + hi.y), 0.5 * (lo.z + hi.z)));
        for k in 0..8u32 {
            let (a, b) = (station * 8 + k, station * 8 + (k + 1) % 8);
            triangles.push(if flip { [centre, a, b] } else { [centre, b, a] });
        }
    }
    TriMesh::new(positions, triangles).unwrap()
}

fn skeleton(joints: &[(&str, Option<usize>, DVec3)]) -> Skeleton {
    Skeleton::new(
        joints
            .iter()
            .map(|(name, parent, p)| Joint {
                name: name.to_string(),
                parent: *parent,
                rest_world_from_joint: DAffine3::from_translation(*p),
            })
            .collect(),
    )
    .unwrap()
}

/// A 4 × 0.4 × 0.4 bar along x with bones 0 → 2 → 4 (joint 0, joint 1) and an end marker.
fn two_bone_bar() -> (TriMesh, Skeleton) {
    let mesh = bar(DVec3::new(0.0, -0.2, -0.2), DVec3::new(4.0, 0.2, 0.2), 40);
    let s = skeleton(&[
        ("upper", None, DVec3::ZERO),
        ("lower", Some(0), DVec3::new(2.0, 0.0, 0.0)),
        ("lower_end", Some(1), DVec3::new(4.0, 0.0, 0.0)),
    ]);
    (mesh, s)
}

fn check_invariants(w: &SkinWeights, max_influences: usize) {
    for v in 0..w.num_vertices() {
        let (joints, weights) = w.row(v);
        assert!(!joints.is_empty(), "vertex {v} unweighted");
        assert!(joints.len() <= max_influences, "vertex {v}: {joints:?}");
        assert!(weights.iter().all(|&x| x > 0.0 && x.is_finite()));
        let sum: f64 = weights.iter().sum();
        assert!((sum - 1.0).abs() < 1e-12, "vertex {v}: sum {sum}");
    }
}

#[test]
fn two_bone_bar_weights_follow_the_nearest_bone() {
    let (mesh, s) = two_bone_bar();
    let r = AutoWeights::new(AutoWeightsOptions {
        resolution: 64,
        ..Default::default()
    })
    .unwrap()
    .compute(&mesh, &s, None)
    .unwrap();
    check_invariants(&r.weights, 4);
    assert_eq!(r.report.deforming_joints, vec![0, 1]);
    assert_eq!(r.report.straight_distance_vertices, 0);
    for (v, p) in mesh.positions.iter().enumerate() {
        let w0 = r.weights.get(v, 0);
        // The end marker never gets weight.
        assert_eq!(r.weights.get(v, 2), 0.0);
        if p.x < 1.5 {
            assert!(w0 > 0.95, "vertex {v} at x = {}: w0 = {w0}", p.x);
        } else if p.x > 2.5 {
            assert!(w0 < 0.05, "vertex {v} at x = {}: w0 = {w0}", p.x);
        }
    }
    // Across the joint the weight of the upper bone decreases monotonically along x.
    let mut along: Vec<(f64, f64)> = mesh
        .positions
        .iter()
        .enumerate()
        .filter(|(_, p)| p.y == -0.2 && p.z == -0.2)
        .map(|(v, p)| (p.x, r.weights.get(v, 0)))
        .collect();
    along.sort_by(|a, b| a.0.total_cmp(&b.0));
    assert!(
        along.windows(2).all(|w| w[1].1 <= w[0].1 + 1e-9),
        "{along:?}"
    );
    // Smooth: neighbouring rings (0.1 apart, a quarter of the bar's width) differ by < 0.25.
    assert!(
        along.windows(2).all(|w| w[0].1 - w[1].1 < 0.25),
        "{along:?}"
    );
    let mid = along.iter().find(|(x, _)| (x - 2.0).abs() < 1e-9).unwrap();
    assert!((mid.1 - 0.5).abs() < 0.1, "{mid:?}");
}

#[test]
fn a_deforming_tip_takes_the_end_of_the_bar_and_influences_are_capped() {
    let (mesh, _) = two_bone_bar();
    let s = skeleton(&[
        ("a", None, DVec3::ZERO),
        ("b", Some(0), DVec3::new(1.0, 0.0, 0.0)),
        ("c", Some(1), DVec3::new(2.0, 0.0, 0.0)),
        ("d", Some(2), DVec3::new(3.0, 0.0, 0.0)),
    ]);
    for k in [1, 2, 3] {
        let r = AutoWeights::new(AutoWeightsOptions {
            max_influences: k,
            resolution: 48,
            exponent: 1.0,
            ..Default::default()
        })
        .unwrap()
        .compute(&mesh, &s, None)
        .unwrap();
        check_invariants(&r.weights, k);
        assert_eq!(r.report.deforming_joints, vec![0, 1, 2, 3]);
        let end = (0..mesh.num_vertices())
            .find(|&v| mesh.positions[v].x == 4.0)
            .unwrap();
        assert_eq!(r.weights.heaviest(end), Some(3));
    }
    // The tip set static: the bar's end goes to its parent.
    let r = AutoWeights::new(AutoWeightsOptions {
        tips: TipJoints::None,
        resolution: 48,
        ..Default::default()
    })
    .unwrap()
    .compute(&mesh, &s, None)
    .unwrap();
    assert_eq!(r.report.deforming_joints, vec![0, 1, 2]);
    assert!((0..mesh.num_vertices()).all(|v| r.weights.get(v, 3) == 0.0));
}

#[test]
fn a_soup_with_a_hole_and_a_second_piece_is_weighted() {
    let (mesh, s) = two_bone_bar();
    // Unweld every triangle, drop one, and add a far piece no bone is in.
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for t in 1..mesh.num_triangles() {
        let base = positions.len() as u32;
        positions.extend(mesh.corners(t));
        triangles.push([base, base + 1, base + 2]);
    }
    let far = TriMesh::cuboid(DVec3::new(0.0, 3.0, 0.0), DVec3::new(0.5, 3.5, 0.5)).unwrap();
    let base = positions.len() as u32;
    positions.extend(&far.positions);
    triangles.extend(far.triangles.iter().map(|t| t.map(|i| i + base)));
    let soup = TriMesh::new(positions, triangles).unwrap();
    let r = AutoWeights::new(AutoWeightsOptions {
        resolution: 64,
        ..Default::default()
    })
    .unwrap()
    .compute(&soup, &s, None)
    .unwrap();
    check_invariants(&r.weights, 4);
    assert_eq!(r.report.straight_distance_vertices, 8);
    assert_eq!(r.report.warnings.len(), 1);
    // The far piece sits above joint 0's bone: it follows joint 0.
    assert_eq!(r.weights.heaviest(soup.num_vertices() - 1), Some(0));
}

#[test]
fn progress_reports_every_joint_and_ends_at_the_weights() {
    let (mesh, s) = two_bone_bar();
    let seen = Mutex::new(Vec::new());
    AutoWeights::new(AutoWeightsOptions {
        resolution: 32,
        ..Default::default()
    })
    .unwrap()
    .compute_with_progress(&mesh, &s, None, &|p| seen.lock().unwrap().push(p))
    .unwrap();
    let seen = seen.into_inner().unwrap();
    let distance_steps = seen.iter().filter(|p| p.stage == Stage::Distances).count();
    assert_eq!(distance_steps, 2);
    assert_eq!(
        seen.last(),
        Some(&Progress {
            stage: Stage::Weights,
            done: 1,
            total: 1
        })
    );
}

#[test]
fn bad_options_and_inputs_are_errors_naming_what_was_expected() {
    let bad = |o: AutoWeightsOptions| AutoWeights::new(o).unwrap_err();
    let e = bad(AutoWeightsOptions {
        max_influences: 0,
        ..Default::default()
    });
    assert!(matches!(
        e,
        AutoWeightsError::InvalidOption {
            option: "max_influences",
            ..
        }
    ));
    let e = bad(AutoWeightsOptions {
        exponent: f64::NAN,
        ..Default::default()
    });
    assert!(e.to_string().contains("NaN"), "{e}");
    let e = bad(AutoWeightsOptions {
        resolution: 4,
        ..Default::default()
    });
    assert!(matches!(
        e,
        AutoWeightsError::InvalidOption {
            option: "resolution",
            ..
        }
    ));

    let (mesh, s) = two_bone_bar();
    let aw = AutoWeights::new(AutoWeightsOptions {
        tips: TipJoints::Only(vec![1]),
        ..Default::default()
    })
    .unwrap();
    assert_eq!(
        aw.compute(&mesh, &s, None).unwrap_err(),
        AutoWeightsError::NotATip {
            joint: 1,
            joints: 3
        }
    );
    let aw = AutoWeights::new(AutoWeightsOptions::default()).unwrap();
    let empty = TriMesh::new(mesh.positions.clone(), Vec::new()).unwrap();
    assert_eq!(
        aw.compute(&empty, &s, None).unwrap_err(),
        AutoWeightsError::NoTriangles {
            vertices: mesh.num_vertices()
        }
    );
    let point = skeleton(&[("only_end", None, DVec3::ZERO)]);
    assert_eq!(
        aw.compute(&mesh, &point, None).unwrap_err(),
        AutoWeightsError::NoDeformingJoint { joints: 1 }
    );
}

#[test]
fn a_cage_keeps_the_volume_of_an_open_bar() {
    let (mesh, s) = two_bone_bar();
    // Remove one end cap and a ring of side quads near the middle: a wide hole.
    let open: Vec<[u32; 3]> = mesh
        .triangles
        .iter()
        .enumerate()
        .filter(|(t, _)| !(18 * 16..22 * 16).contains(t))
        .map(|(_, t)| *t)
        .collect();
    let open = TriMesh::new(mesh.positions.clone(), open).unwrap();
    let cage = TriMesh::cuboid(DVec3::new(-0.1, -0.3, -0.3), DVec3::new(4.1, 0.3, 0.3)).unwrap();
    let aw = AutoWeights::new(AutoWeightsOptions {
        resolution: 64,
        ..Default::default()
    })
    .unwrap();
    let without = aw.compute(&open, &s, None).unwrap();
    let with = aw.compute(&open, &s, Some(&cage)).unwrap();
    assert!(with.report.solid_voxels > without.report.solid_voxels);
    check_invariants(&with.weights, 4);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]
    #[test]
    fn random_chains_give_valid_weights(
        points in proptest::collection::vec((0.0f64..4.0, -0.15f64..0.15, -0.15f64..0.15), 2..6),
        k in 1usize..5,
        p in 1.0f64..8.0,
    ) {
        let (mesh, _) = two_bone_bar();
        let names: Vec<String> = (0..points.len()).map(|i| format!("j{i}")).collect();
        let joints: Vec<(&str, Option<usize>, DVec3)> = points
            .iter()
            .enumerate()
            .map(|(i, &(x, y, z))| (names[i].as_str(), i.checked_sub(1), DVec3::new(x, y, z)))
            .collect();
        let s = skeleton(&joints);
        let r = AutoWeights::new(AutoWeightsOptions {
            max_influences: k,
            resolution: 24,
            exponent: p,
            ..Default::default()
        })
        .unwrap()
        .compute(&mesh, &s, None)
        .unwrap();
        check_invariants(&r.weights, k);
        for v in 0..mesh.num_vertices() {
            for &j in r.weights.row(v).0 {
                prop_assert!(r.report.deforming_joints.contains(&(j as usize)));
            }
        }
    }
}

/// A chain of four bones along the bar (joints `j0` … `j3` and the end marker `j4_end` at
/// x = 0 … 4), scaled by `scale` about the origin and moved by `offset`.
fn moved_chain(offset: DVec3, scale: f64) -> Skeleton {
    let names = ["j0", "j1", "j2", "j3", "j4_end"];
    let joints: Vec<(&str, Option<usize>, DVec3)> = names
        .iter()
        .enumerate()
        .map(|(i, name)| {
            let x = DVec3::new(i as f64, 0.0, 0.0);
            (*name, i.checked_sub(1), offset + scale * x)
        })
        .collect();
    skeleton(&joints)
}

#[test]
fn a_skeleton_outside_the_mesh_is_refused_naming_its_joints_and_distances() {
    let (mesh, _) = two_bone_bar();
    let aw = AutoWeights::new(AutoWeightsOptions::default()).unwrap();
    // Shifted 100 units: every bone is far from the body.
    let shifted = moved_chain(DVec3::new(0.0, 100.0, 0.0), 1.0);
    let e = aw.compute(&mesh, &shifted, None).unwrap_err();
    let AutoWeightsError::SkeletonOutsideMesh {
        outside, deforming, ..
    } = &e
    else {
        panic!("expected SkeletonOutsideMesh, got {e}");
    };
    assert_eq!((*outside, *deforming), (4, 4));
    let text = e.to_string();
    assert!(text.contains("j0 99.") && text.contains("j3 99."), "{text}");
    assert!(text.contains("share units, scale and origin"), "{text}");
    // Scaled ×100 about the bar's end: the first bone crosses the bar, the others are far.
    let scaled = moved_chain(DVec3::ZERO, 100.0);
    let e = aw.compute(&mesh, &scaled, None).unwrap_err();
    assert!(
        matches!(
            e,
            AutoWeightsError::SkeletonOutsideMesh {
                outside: 3,
                deforming: 4,
                ..
            }
        ),
        "{e}"
    );
    // The same chain inside the bar is weighted with no warning.
    let inside = moved_chain(DVec3::ZERO, 1.0);
    let r = aw.compute(&mesh, &inside, None).unwrap();
    assert!(r.report.warnings.is_empty(), "{:?}", r.report.warnings);
}

#[test]
fn one_joint_outside_the_mesh_is_a_warning_naming_it() {
    let (mesh, _) = two_bone_bar();
    let s = skeleton(&[
        ("upper", None, DVec3::ZERO),
        ("lower", Some(0), DVec3::new(2.0, 0.0, 0.0)),
        ("arm", Some(1), DVec3::new(3.0, 0.0, 0.0)),
        ("arm_end", Some(2), DVec3::new(4.0, 0.0, 0.0)),
        ("antenna", Some(0), DVec3::new(1.0, 3.0, 0.0)),
        ("antenna_end", Some(4), DVec3::new(1.0, 4.0, 0.0)),
    ]);
    let aw = AutoWeights::new(AutoWeightsOptions::default()).unwrap();
    let r = aw.compute(&mesh, &s, None).unwrap();
    let notes: Vec<String> = r.report.warnings.iter().map(ToString::to_string).collect();
    assert!(
        notes
            .iter()
            .any(|n| n.starts_with("1 of the 4 deforming joints lie outside the mesh: antenna 2.")),
        "{notes:?}"
    );
}
