//! The display path's rest-skin product M̃ = Φ̃·C per event on the wgpu backend ([`GpuRestMap`]:
//! upload of the cage, one compute pass, readback into the session's buffer) against the CPU
//! backend (`DisplayCageCoords`, Φ rounded to f32, f64 sums on the rayon pool) and the wgpu
//! product's own CPU fallback, on the Arm subdivided N times (mean value coordinates, 74 cage
//! vertices), with the error of each against the exact M as a fraction of the diagonal.
//!
//! `cargo run --release -p cagerig-render --example rest_map_bench -- [LEVELS] [REPS]`
//! (LEVELS: comma-separated subdivision levels, default `0,3`: 2,089 and 133,073 vertices;
//! REPS: timed products per backend, default 50, after 3 untimed ones).

// tests, benches and examples may panic on a broken fixture

use std::time::Instant;

use cagerig::cage_coords::DisplayCageCoords;
use cagerig::session::{DisplayRestMapProduct, RigParts, RigSession, SessionOptions};
use cagerig_render::GpuRestMap;
use glam::{DVec3, Vec3};

/// "median (min) ms" of `samples`.
fn stats(mut samples: Vec<f64>) -> String {
    samples.sort_by(f64::total_cmp);
    format!(
        "median {:.3} ms (min {:.3})",
        samples[samples.len() / 2],
        samples[0]
    )
}

fn relative_error(shown: &[Vec3], exact: &[DVec3]) -> f64 {
    let lo = exact.iter().fold(DVec3::INFINITY, |a, &p| a.min(p));
    let hi = exact.iter().fold(DVec3::NEG_INFINITY, |a, &p| a.max(p));
    let worst = shown
        .iter()
        .zip(exact)
        .map(|(a, b)| a.as_dvec3().distance(*b))
        .fold(0.0, f64::max);
    worst / (hi - lo).length()
}

/// Times `product` over `reps` events (cage vertex 7 nudged each time), returns the samples (ms).
fn time(
    cage: &mut [DVec3],
    reps: usize,
    out: &mut [Vec3],
    mut product: impl FnMut(&[DVec3], &mut [Vec3]),
) -> Vec<f64> {
    let mut samples = Vec::with_capacity(reps);
    for rep in 0..reps + 3 {
        let sign = if rep % 2 == 0 { 1.0 } else { -1.0 };
        cage[7].y += sign * 1e-3;
        let t = Instant::now();
        product(cage, out);
        if rep >= 3 {
            samples.push(t.elapsed().as_secs_f64() * 1e3);
        }
    }
    samples
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let levels: Vec<usize> = args
        .get(1)
        .map_or("0,3", String::as_str)
        .split(',')
        .map(str::parse)
        .collect::<Result<_, _>>()?;
    let reps: usize = args.get(2).map_or(Ok(50), |s| s.parse())?;
    let gpu = GpuRestMap::new_headless()?;
    println!(
        "wgpu on {}, CPU backend on {} rayon threads",
        gpu.adapter_name(),
        rayon::current_num_threads()
    );
    let arm = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/arm/arm.obj");
    let rig = cagerig::rig_files::load_rig_files(std::path::Path::new(arm), None)?.parts;
    for level in levels {
        let sub = cagerig::subdivide::subdivide_midpoint(&rig.mesh, &rig.skin_weights, level)?;
        let parts = RigParts::new(
            sub.mesh,
            rig.skeleton.clone(),
            sub.skin_weights,
            rig.cage.clone(),
        );
        let (session, _) = RigSession::new(parts, SessionOptions::default())?;
        let phi = session.cage_coords();
        let (nv, nc) = (phi.num_vertices(), phi.num_cage_vertices());
        let mut cage = session.rest_cage().to_vec();
        let cpu = DisplayCageCoords::try_new(phi).ok_or("Φ̃ does not fit in memory")?;
        let t = Instant::now();
        let on_gpu = gpu.bind(&[phi])?;
        let bind_ms = t.elapsed().as_secs_f64() * 1e3;
        println!(
            "Arm N={level}: {nv} vertices × {nc} cage vertices ({:.1} MB of f32 coefficients; \
             binding {bind_ms:.1} ms)",
            (nv * (nc + 1) * 4) as f64 / 1e6
        );
        let mut out = vec![Vec3::ZERO; nv];
        let mut exact = vec![DVec3::ZERO; nv];
        let wgpu_ms = time(&mut cage, reps, &mut out, |c, o| on_gpu.apply(c, &[], o));
        phi.apply(&cage, &mut exact);
        let wgpu_error = relative_error(&out, &exact);
        let cpu_ms = time(&mut cage, reps, &mut out, |c, o| cpu.apply(c, o));
        phi.apply(&cage, &mut exact);
        let cpu_error = relative_error(&out, &exact);
        let fallback_ms = time(&mut cage, reps, &mut out, |c, o| {
            on_gpu.apply_on_cpu(c, &[], o);
        });
        println!(
            "  wgpu apply (upload, pass, readback): {}, error {wgpu_error:.1e} of the diagonal",
            stats(wgpu_ms)
        );
        println!(
            "  CPU backend (DisplayCageCoords):     {}, error {cpu_error:.1e} of the diagonal",
            stats(cpu_ms)
        );
        println!(
            "  wgpu product's CPU fallback:         {}",
            stats(fallback_ms)
        );
        if on_gpu.has_failed() {
            println!("  (the GPU failed: {:?})", gpu.first_failure());
        }
    }
    Ok(())
}
