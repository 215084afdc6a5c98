//! Λ = S·Φ (CoR centres in cage coordinates, Eq. 14) on the Arm subdivided N times (default 3:
//! 133 073 vertices): timing, peak memory and centre error against the exact Eq. 5 (all vertices
//! for small N, a sample of vertices otherwise).
//!
//! `cargo run --release -p cagerig --example cor_bench [-- LEVELS [SAMPLES]]`
//! Environment: MODE = grid (default; [`compute_cor_cage_coords_grid`]) or clustered
//! ([`compute_cor_cage_coords`]); STEP (grid step, default 1/32 as in `CorGridOptions::default`), BINS (bin resolution, 128),
//! INTERP (cubic | linear) for the grid; VSTEP, PSTEP, FLOOR, MASSTOL for the clustering.

// tests, benches and examples may panic on a broken fixture

use std::path::Path;
use std::time::Instant;

use cagerig::SkinWeights;
use cagerig::coords::mvc::compute_cage_coords;
use cagerig::cor_centres::weight_similarity;
use cagerig::io::{read_obj, read_skt, read_skw};
use cagerig::mesh::bounding_box;
use cagerig::skinning::{
    CorCentresMethod, CorCentresOptions, CorGridOptions, GridInterpolation,
    compute_cor_cage_coords, compute_cor_cage_coords_grid,
};
use cagerig::subdivide::subdivide_midpoint;
use glam::DVec3;
use rayon::prelude::*;

const ARM: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/arm");

/// Peak resident memory so far (MB), from /proc (0 where unavailable).
fn peak_rss_mb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        })
        .map_or(0.0, |kb| kb / 1024.0)
}

fn env(name: &str, default: f64) -> f64 {
    std::env::var(name)
        .ok()
        .and_then(|x| x.parse().ok())
        .unwrap_or(default)
}

/// Exact Eq. 5 centre of vertex i (no clustering, no pruning) from per-triangle data.
fn exact_centre(
    i: usize,
    rest: &[DVec3],
    weights: &SkinWeights,
    triangles: &[(f64, DVec3, Vec<u32>, Vec<f64>)],
    inv_sigma_sq: f64,
) -> DVec3 {
    let (js, ws) = weights.row(i);
    if js.len() < 2 {
        return rest[i];
    }
    let (mut num, mut den) = (DVec3::ZERO, 0.0);
    for (area, centroid, tj, tw) in triangles {
        let s = weight_similarity(js, ws, tj, tw, inv_sigma_sq) * area;
        num += s * *centroid;
        den += s;
    }
    if den > 0.0 { num / den } else { rest[i] }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let levels: usize = args.get(1).map_or(Ok(3), |a| a.parse())?;
    let samples: usize = args.get(2).map_or(Ok(300), |a| a.parse())?;
    let arm = Path::new(ARM);
    let mesh = read_obj(&arm.join("arm.obj"))?;
    let cage = read_obj(&arm.join("arm_cage.obj"))?;
    let skeleton = read_skt(&arm.join("arm.skt"))?;
    let (weights, _) = read_skw(&arm.join("arm.skw"), mesh.num_vertices(), skeleton.len())?;
    let sub = subdivide_midpoint(&mesh, &weights, levels)?;
    let (rest, tris, weights) = (sub.mesh.positions, sub.mesh.triangles, sub.skin_weights);
    let n = rest.len();
    let (lo, hi) = bounding_box(&rest);
    let diag = (hi - lo).length();
    println!(
        "Arm, {levels} subdivision levels: {n} vertices, {} triangles",
        tris.len()
    );

    let start = Instant::now();
    let phi = compute_cage_coords(&cage, &rest, None)?;
    println!(
        "MVC Φ ({n} × {}): {:.2?} (peak RSS {:.0} MB)",
        phi.num_cage_vertices(),
        start.elapsed(),
        peak_rss_mb()
    );
    let before = peak_rss_mb();

    let mode = std::env::var("MODE").unwrap_or_else(|_| "grid".into());
    let start = Instant::now();
    let (lambda, label) = if mode == "clustered" {
        let options = CorCentresOptions {
            method: CorCentresMethod::Clustered {
                vertex_step: env("VSTEP", 0.01),
                patch_step: env("PSTEP", 0.05),
                weight_floor: env("FLOOR", 0.0),
            },
            mass_tolerance: env("MASSTOL", 1e-5),
            ..Default::default()
        };
        let lambda = compute_cor_cage_coords(&rest, &tris, &weights, &phi, &options, &|_, _| {})?;
        (lambda, format!("{:?}", options.method))
    } else {
        let options = CorGridOptions {
            grid_step: env("STEP", CorGridOptions::default().grid_step),
            bin_resolution: env("BINS", 128.0),
            interpolation: if std::env::var("INTERP").as_deref() == Ok("linear") {
                GridInterpolation::Bilinear
            } else {
                GridInterpolation::Bicubic
            },
            ..Default::default()
        };
        let lambda =
            compute_cor_cage_coords_grid(&rest, &tris, &weights, &phi, &options, &|_, _| {})?;
        (lambda, format!("{options:?}"))
    };
    let elapsed = start.elapsed();
    println!(
        "Λ = S·Φ ({label}): {elapsed:.2?}, peak RSS {:.0} MB (before {before:.0} MB, Λ itself {:.0} MB)",
        peak_rss_mb(),
        (n * phi.num_cage_vertices() * 8) as f64 / 1e6
    );
    let mut centres = vec![DVec3::ZERO; n];
    lambda.apply(&cage.positions, &mut centres);
    let unity = (0..n)
        .map(|i| {
            let sum: f64 = (0..phi.num_cage_vertices()).map(|k| lambda.get(i, k)).sum();
            (sum - 1.0).abs()
        })
        .fold(0.0, f64::max);
    println!("max |Σ_c Λ_ic − 1| = {unity:e}");

    // Exact Eq. 5 on every vertex (small meshes) or a deterministic sample.
    let triangles: Vec<(f64, DVec3, Vec<u32>, Vec<f64>)> = tris
        .iter()
        .filter_map(|&[a, b, c]| {
            let (pa, pb, pc) = (rest[a as usize], rest[b as usize], rest[c as usize]);
            let area = 0.5 * (pb - pa).cross(pc - pa).length();
            if area <= 0.0 {
                return None;
            }
            let mut row = std::collections::BTreeMap::new();
            for v in [a, b, c] {
                let (js, ws) = weights.row(v as usize);
                for (&j, &w) in js.iter().zip(ws) {
                    *row.entry(j).or_insert(0.0) += w / 3.0;
                }
            }
            Some((
                area,
                (pa + pb + pc) / 3.0,
                row.keys().copied().collect(),
                row.values().copied().collect(),
            ))
        })
        .collect();
    let checked: Vec<usize> = if n <= 3000 {
        (0..n).collect()
    } else {
        (0..samples).map(|s| (s * 7919 * 13 + 17) % n).collect()
    };
    let start = Instant::now();
    let errors: Vec<f64> = checked
        .par_iter()
        .map(|&i| exact_centre(i, &rest, &weights, &triangles, 100.0).distance(centres[i]) / diag)
        .collect();
    let max = errors.iter().copied().fold(0.0, f64::max);
    let mean = errors.iter().sum::<f64>() / errors.len() as f64;
    println!(
        "centre error vs exact Eq. 5 on {} vertices ({:.2?}): max {max:.3e}, mean {mean:.3e} of bbox diagonal {diag:.3}",
        checked.len(),
        start.elapsed()
    );
    Ok(())
}
