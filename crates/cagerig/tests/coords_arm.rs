//! Coordinate kernels on the paper's Arm example: MVC vs the shipped cage weights, MaxVol vs the
//! shipped selection, max-entropy joint coordinates (including the joint the reference fails on).

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

use std::time::Instant;

use cagerig::coords::maxvol::{
    MaxVolOptions, log_abs_det_of_rows, refine_maxvol_rows, select_maxvol_rows,
    select_maxvol_rows_with,
};
use cagerig::coords::mec::{MecMethod, max_entropy_coordinates};
use cagerig::coords::mvc::{compute_cage_coords, mean_value_coordinates};
use cagerig::{CageCoords, TriMesh};
use faer::Mat;
use faer::linalg::solvers::DenseSolveCore;
use glam::DVec3;

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod support;
use support::{ARM, mesh as load_obj, read};

/// `<column> <row> <weight>` triplets into a dense `rows × cols` matrix.
fn load_triplets(name: &str, rows: usize, cols: usize) -> Mat<f64> {
    let mut m = Mat::zeros(rows, cols);
    for line in read(name).lines() {
        if line.starts_with('#') || line.trim().is_empty() {
            continue;
        }
        let f: Vec<&str> = line.split_whitespace().collect();
        let (col, row): (usize, usize) = (f[0].parse().unwrap(), f[1].parse().unwrap());
        m[(row, col)] = f[2].parse().unwrap();
    }
    m
}

fn load_joints() -> Vec<(String, DVec3)> {
    read("arm.skt")
        .lines()
        .filter(|l| l.starts_with("j "))
        .map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            let p: Vec<f64> = f[4..7].iter().map(|s| s.parse().unwrap()).collect();
            (f[2].to_string(), DVec3::new(p[0], p[1], p[2]))
        })
        .collect()
}

fn shipped_maxvol_rows() -> Vec<usize> {
    let text = read("arm_cage.maxvol");
    let mut it = text.split_whitespace();
    assert_eq!(it.next(), Some("MAXVOLSELECTION"));
    let n: usize = it.next().unwrap().parse().unwrap();
    let rows: Vec<usize> = it.map(|s| s.parse().unwrap()).collect();
    assert_eq!(rows.len(), n);
    rows
}

#[test]
fn mvc_reproduces_shipped_cage_weights() {
    let mesh = load_obj("arm.obj");
    let cage = load_obj("arm_cage.obj");
    assert_eq!((mesh.num_vertices(), cage.num_vertices()), (2089, 58));
    let reference = load_triplets("arm_cage_cageWeights.txt", 2089, 58);
    let phi = compute_cage_coords(&cage, &mesh.positions, None).unwrap();
    let mut worst = 0.0f64;
    for i in 0..2089 {
        for k in 0..58 {
            worst = worst.max((phi.get(i, k) - reference[(i, k)]).abs());
        }
    }
    println!("max |Φ − Φ_file| = {worst:e}");
    assert!(worst <= 5e-6, "max difference {worst}");
    assert!(phi.max_partition_error() < 1e-12);
    let mut rebuilt = vec![DVec3::ZERO; 2089];
    phi.apply(&cage.positions, &mut rebuilt);
    let err = cagerig::mesh::max_distance(&rebuilt, &mesh.positions);
    println!("max |ΦC − M| = {err:e}");
    assert!(err < 1e-9);
}

#[test]
fn maxvol_beats_shipped_selection() {
    let mesh = load_obj("arm.obj");
    let cage = load_obj("arm_cage.obj");
    let ours = compute_cage_coords(&cage, &mesh.positions, None).unwrap();
    let file =
        CageCoords::from_matrix(load_triplets("arm_cage_cageWeights.txt", 2089, 58)).unwrap();
    let shipped = shipped_maxvol_rows();
    for (label, phi) in [("our MVC", &ours), ("file", &file)] {
        let start = Instant::now();
        let sel = select_maxvol_rows(phi).unwrap();
        let elapsed = start.elapsed();
        let shipped_det = log_abs_det_of_rows(phi, &shipped).unwrap();
        let refined = refine_maxvol_rows(phi, &shipped).unwrap();
        println!(
            "shipped rows refined: ln|det| = {:.6} ({} swaps: already dominant)",
            refined.log_abs_det, refined.swaps
        );
        println!(
            "Φ from {label}: ours ln|det| = {:.6} ({} swaps, {:.2?}), shipped = {shipped_det:.6}",
            sel.log_abs_det, sel.swaps, elapsed
        );
        assert!(sel.log_abs_det >= shipped_det - 1e-9);
        let mut sorted = sel.rows.clone();
        sorted.sort();
        sorted.dedup();
        assert_eq!(sorted.len(), 58);
    }
}

#[test]
fn mec_joint_coordinates_satisfy_constraints_for_every_joint() {
    let mesh = load_obj("arm.obj");
    let cage = load_obj("arm_cage.obj");
    let phi = compute_cage_coords(&cage, &mesh.positions, None).unwrap();
    let joints = load_joints();
    assert_eq!(joints.len(), 25);
    let psi_ref = load_triplets("reference/s0_skelUpdaterWeights_psi.txt", 25, 58);
    let mut mvc = vec![0.0; mesh.num_vertices()];
    let mut psi = vec![0.0; 58];
    for (j, (name, position)) in joints.iter().enumerate() {
        // Prior 1 (the reference tool's fallback prior): μ = Φᵀ m, m = MVC of the joint w.r.t.
        // the character mesh. Prior 2: the reference Ψ row itself (slightly negative entries).
        mean_value_coordinates(&mesh.positions, &mesh.triangles, *position, &mut mvc);
        let projected: Vec<f64> = (0..58)
            .map(|k| phi.column(k).iter().zip(&mvc).map(|(a, b)| a * b).sum())
            .collect();
        let reference_row: Vec<f64> = (0..58).map(|k| psi_ref[(j, k)]).collect();
        for (label, prior) in [("Φᵀ·mvc", &projected), ("Ψ_ref", &reference_row)] {
            let report = max_entropy_coordinates(&cage.positions, prior, *position, &mut psi);
            let sum: f64 = psi.iter().sum();
            let combo: DVec3 = cage.positions.iter().zip(&psi).map(|(c, w)| *w * *c).sum();
            println!(
                "joint {j:2} {name:14} prior {label:7}: {:?} it {:2} residual {:.2e} clamped {}",
                report.method, report.iterations, report.residual, report.clamped_masses
            );
            assert!(combo.distance(*position) <= 1e-10, "{report:?}");
            assert!((sum - 1.0).abs() <= 1e-10);
            assert!((report.residual - combo.distance(*position)).abs() < 1e-12);
            // Every Arm joint is strictly inside the cage: MEC proper must succeed.
            assert_eq!(
                report.method,
                MecMethod::MaxEntropy,
                "joint {j}: {report:?}"
            );
            assert!(psi.iter().all(|w| *w > 0.0));
        }
    }
}

/// Timings (run with `cargo test --release -p cagerig --test coords_arm -- --ignored --nocapture`).
#[test]
#[ignore]
fn timing_mvc_and_maxvol() {
    let mesh = load_obj("arm.obj");
    let cage = load_obj("arm_cage.obj");
    let (lo, hi) = cage.bounding_box();
    let time = |label: &str, points: &[DVec3]| -> CageCoords {
        let mut best = f64::INFINITY;
        let mut phi = None;
        for _ in 0..5 {
            let start = Instant::now();
            phi = Some(compute_cage_coords(&cage, points, None).unwrap());
            best = best.min(start.elapsed().as_secs_f64() * 1e3);
        }
        println!(
            "MVC {label}: {} points, best of 5: {best:.1} ms ({} threads)",
            points.len(),
            rayon::current_num_threads()
        );
        phi.unwrap()
    };
    time("Arm", &mesh.positions);
    // ~133k points: the Arm vertices jittered 64 times (stay near the surface, like a dense skin).
    let mut state = 12345u64;
    let mut rnd = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    };
    let extent = (hi - lo).length();
    let dense: Vec<DVec3> = (0..64)
        .flat_map(|_| mesh.positions.clone())
        .map(|p| p + 0.01 * extent * DVec3::new(rnd(), rnd(), rnd()))
        .collect();
    let phi = time("dense", &dense);
    for starts in [1, 16] {
        let mut best = f64::INFINITY;
        let mut sel = None;
        for _ in 0..3 {
            let start = Instant::now();
            sel = Some(
                select_maxvol_rows_with(
                    &phi,
                    &MaxVolOptions {
                        starts,
                        starts_all_rows: starts,
                        ..Default::default()
                    },
                )
                .unwrap(),
            );
            best = best.min(start.elapsed().as_secs_f64() * 1e3);
        }
        let sel = sel.unwrap();
        println!(
            "MaxVol on {} × 58, {starts} starts: best of 3: {best:.1} ms ({} swaps, ln|det| {:.4})",
            phi.num_vertices(),
            sel.swaps,
            sel.log_abs_det
        );
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    pool.install(|| {
        let start = Instant::now();
        compute_cage_coords(&cage, &dense, None).unwrap();
        let ms = start.elapsed().as_secs_f64() * 1e3;
        println!(
            "MVC dense single thread: {ms:.1} ms = {:.2} µs/point",
            ms * 1e3 / dense.len() as f64
        );
    });
}

/// The Arm subdivided twice (33k vertices) and its Φ.
fn subdivided_arm(levels: usize) -> (TriMesh, TriMesh) {
    use cagerig::io::{read_obj, read_skt, read_skw};
    let dir = std::path::Path::new(ARM);
    let mesh = read_obj(&dir.join("arm.obj")).unwrap();
    let cage = read_obj(&dir.join("arm_cage.obj")).unwrap();
    let skeleton = read_skt(&dir.join("arm.skt")).unwrap();
    let (weights, _) = read_skw(&dir.join("arm.skw"), mesh.num_vertices(), skeleton.len()).unwrap();
    let dense = cagerig::subdivide::subdivide_midpoint(&mesh, &weights, levels)
        .unwrap()
        .mesh;
    (dense, cage)
}

#[test]
fn batched_mvc_matches_scalar_evaluator_on_subdivided_arm() {
    let (mesh, cage) = subdivided_arm(1);
    let phi = compute_cage_coords(&cage, &mesh.positions, None).unwrap();
    let evaluator = cagerig::coords::mvc::MvcEvaluator::new(&cage.positions, &cage.triangles);
    let mut scratch = evaluator.scratch();
    let mut row = vec![0.0; cage.num_vertices()];
    let mut worst = 0.0f64;
    for (i, &x) in mesh.positions.iter().enumerate() {
        evaluator.evaluate(x, &mut scratch, &mut row);
        for (k, &w) in row.iter().enumerate() {
            worst = worst.max((phi.get(i, k) - w).abs());
        }
    }
    println!("N=1: max |Φ_batch − Φ_scalar| = {worst:e}");
    // Both use few-ulp arctangents; near-surface vertices amplify rounding (cancelling
    // per-triangle terms), so the agreement is ~1e-12, not 1e-16.
    assert!(worst < 1e-11, "max difference {worst:e}");
    assert!(phi.max_partition_error() < 1e-12);
}

#[test]
fn maxvol_on_subdivided_arm_is_dominant() {
    let (mesh, cage) = subdivided_arm(2);
    let phi = compute_cage_coords(&cage, &mesh.positions, None).unwrap();
    let sel = select_maxvol_rows(&phi).unwrap();
    println!(
        "N=2: ln|det| = {:.6} ({} swaps)",
        sel.log_abs_det, sel.swaps
    );
    // Value of the implementation without bound-pruned dominance checks.
    assert!(sel.log_abs_det >= -49.014554 - 1e-6);
    let inverse = phi.select_rows(&sel.rows).partial_piv_lu().inverse();
    let b = phi.matrix() * &inverse;
    let mut worst = 0.0f64;
    for k in 0..b.ncols() {
        for i in 0..b.nrows() {
            worst = worst.max(b[(i, k)].abs());
        }
    }
    println!("max |Φ Φ̃⁻¹| = {worst}");
    assert!(worst <= cagerig::coords::maxvol::SWAP_THRESHOLD + 1e-9);
}
