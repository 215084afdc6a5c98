//! Times the binding (precomputation) of the Arm subdivided N times: Φ (MVC), MaxVol, Ψ
//! (SkelUp), the CageUp factorisation and, with `--cor`, the CoR centres Λ.
//! `cargo run --release -p cagerig --example bind_bench -- [N] [--cor] [--reps R] [--sweep]`
//! (`RAYON_NUM_THREADS=1` for the single-thread figures; `--sweep`: MaxVol with 1–32 starts).

use std::path::Path;

use cagerig::coords::maxvol::select_maxvol_rows;
use cagerig::coords::mvc::compute_cage_coords;
use cagerig::skinning::CorCentresOptions;
use cagerig::sync::cage_updater::{CageFitMode, CageUpdater};
use cagerig::sync::skeleton_updater::{JointLocalisation, SkeletonUpdater};

mod timing;
use timing::timed;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let levels: usize = args
        .iter()
        .find(|a| !a.starts_with("--") && a.parse::<usize>().is_ok())
        .map_or(Ok(0), |a| a.parse())?;
    let with_cor = args.iter().any(|a| a == "--cor");
    let reps: usize = args
        .iter()
        .position(|a| a == "--reps")
        .and_then(|i| args.get(i + 1))
        .map_or(Ok(if levels >= 3 { 3 } else { 21 }), |a| a.parse())?;
    let arm_obj = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/arm/arm.obj");
    let arm = cagerig::rig_files::load_rig_files(&arm_obj, None)?.parts;
    let (mesh, skeleton, weights, cage) = (arm.mesh, arm.skeleton, arm.skin_weights, arm.cage);
    let sub = cagerig::subdivide::subdivide_midpoint(&mesh, &weights, levels)?;
    let (mesh, weights) = (sub.mesh, sub.skin_weights);
    println!(
        "Arm N={levels}: {} vertices, {} threads, {reps} runs (median / min ms)",
        mesh.num_vertices(),
        rayon::current_num_threads()
    );
    let ((mvc_med, mvc_min), phi) =
        timed(reps, || compute_cage_coords(&cage, &mesh.positions, None));
    let phi = phi?;
    println!("  MVC Φ              {mvc_med:9.3} {mvc_min:9.3}");
    let ((mv_med, mv_min), selection) = timed(reps, || select_maxvol_rows(&phi));
    let selection = selection?;
    println!(
        "  MaxVol             {mv_med:9.3} {mv_min:9.3}   ln|det| {:.6}, {} swaps",
        selection.log_abs_det, selection.swaps
    );
    if args.iter().any(|a| a == "--sweep") {
        for starts in [1, 2, 3, 4, 6, 8, 12, 16, 32] {
            let options = cagerig::coords::maxvol::MaxVolOptions {
                starts,
                starts_all_rows: starts,
                ..Default::default()
            };
            let ((med, min), sel) = timed(reps, || {
                cagerig::coords::maxvol::select_maxvol_rows_with(&phi, &options)
            });
            let sel = sel?;
            println!(
                "    {starts:2} starts   {med:9.3} {min:9.3}   ln|det| {:.6}, {} swaps",
                sel.log_abs_det, sel.swaps
            );
        }
    }
    let ((su_med, su_min), skelup) = timed(reps, || {
        SkeletonUpdater::new(
            &mesh,
            &skeleton,
            &weights,
            &phi,
            None,
            &cage.positions,
            JointLocalisation::default(),
        )
    });
    skelup?;
    println!("  SkelUp Ψ           {su_med:9.3} {su_min:9.3}");
    let ((cu_med, cu_min), cageup) = timed(reps, || {
        CageUpdater::new(&phi, selection.rows.clone(), CageFitMode::Interpolate)
    });
    cageup?;
    println!("  CageUp factorise   {cu_med:9.3} {cu_min:9.3}");
    println!(
        "  Φ + MaxVol + Ψ     {:9.3} {:9.3}",
        mvc_med + mv_med + su_med,
        mvc_min + mv_min + su_min
    );
    if with_cor {
        let ((cor_med, cor_min), lambda) = timed(reps.min(3), || {
            cagerig::session::compute_centre_coords(
                &mesh.positions,
                &mesh.triangles,
                &weights,
                &phi,
                &CorCentresOptions::default(),
            )
        });
        lambda?;
        println!(
            "  CoR centres Λ      {cor_med:9.3} {cor_min:9.3}   ({})",
            cagerig::session::centre_coords_method(mesh.num_vertices())
        );
        println!(
            "  Φ + MaxVol + Ψ + Λ {:9.3} {:9.3}",
            mvc_med + mv_med + su_med + cor_med,
            mvc_min + mv_min + su_min + cor_min
        );
    }
    Ok(())
}
