//! `cagerig bench`: per-operator timings in the layout of the paper's Table 1 (and more).
//!
//! Every figure is the median of repeated runs (with min and max) after a warm-up. Per-frame
//! figures also print the bytes the kernel must move at least (an estimate from the data sizes)
//! and the bandwidth that implies. Kernels run in f64 unless a row says f32. Every model is
//! measured twice, with the default thread pool and on one thread; the printed table
//! (`bench_table`) sets both beside the paper tool's single-threaded figures where the model is
//! the Arm at a size the tool was measured on.

use std::path::PathBuf;

use anyhow::Context;
use cagerig::cage_coords::CoordsPrecision;
use cagerig::coords::{maxvol, mvc};
use cagerig::playback::AnimationPlayer;
use cagerig::session::{DisplayPrecision, RigParts, RigSession, SessionOptions};
use cagerig::skinning::{
    CorF32, CorF32Scratch, CorScratch, CorSkinning, DqsF32, DqsF32Scratch, DqsScratch,
    DualQuaternionSkinning, LbsF32, LbsF32Scratch, LinearBlendSkinning,
};
use cagerig::sync::cage_updater::{CageFitMode, CageUpdater};
use cagerig::sync::skeleton_updater::{JointLocalisation, SkeletonUpdater};
use glam::{DAffine3, DVec3};

use crate::bench_events::{bench_cage_events, synthetic_tracks};
use crate::bench_report::{ModelReport, ModelRow, peak_memory_mb, time};

#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    /// Character mesh (OBJ) with its companions; default: the built-in rig.
    pub mesh: Option<PathBuf>,
    /// Cage (OBJ); default `<stem>_cage.obj` beside the mesh.
    #[arg(long)]
    pub cage: Option<PathBuf>,
    /// Built-in rig when no mesh is given.
    #[arg(long, default_value = "snake")]
    pub builtin: String,
    /// Resolution of the built-in rig.
    #[arg(long)]
    pub resolution: Option<usize>,
    /// Levels of midpoint subdivision; a comma-separated list benches several models.
    #[arg(long, value_delimiter = ',', default_value = "0")]
    pub subdivide: Vec<usize>,
    /// Machine-readable output: an array with one object per model.
    #[arg(long)]
    pub json: bool,
    /// Skip the second pass on one thread (`RAYON_NUM_THREADS=1` like for like with the
    /// single-threaded paper tool); by default every row is measured both ways (`--coords
    /// green` times its rows on every thread only).
    #[arg(long)]
    pub skip_one_thread: bool,
    /// Multiplies the number of repetitions.
    #[arg(long, default_value_t = 1.0)]
    pub repeat_scale: f64,
    /// Cage coordinates of the session rows: `green` benches binding (against MVC), the
    /// per-event rows and their Newton iterations for a Green rig (docs/green-coordinates.md).
    #[arg(long, value_parser = crate::session_args::kind_parser::<cagerig::CoordsKind>(), default_value = "mvc")]
    pub coords: cagerig::CoordsKind,
    /// CageUp's fit in the timed sessions (with `--coords green`, in both its Green and its
    /// mean value sessions).
    #[arg(long, value_parser = crate::session_args::kind_parser::<cagerig::CageFitKind>(), default_value = cagerig::CageFitKind::default().name())]
    pub cage_fit: cagerig::CageFitKind,
}

fn load_parts(args: &Args) -> anyhow::Result<(String, RigParts)> {
    let rig_args = crate::rig_source::RigArgs {
        mesh: args.mesh.clone(),
        cage: args.cage.clone(),
        builtin: args.mesh.is_none().then(|| args.builtin.clone()),
        resolution: if args.mesh.is_none() {
            args.resolution
        } else {
            None
        },
        skin: None,
        allow_outside_cage: false,
        weights: None,
        skeleton: None,
        auto_weights: false,
    };
    let loaded = crate::rig_source::load_rig(&rig_args, false, false)?;
    Ok((loaded.name, loaded.parts))
}

pub fn run(args: &Args) -> anyhow::Result<()> {
    let (name, base) = load_parts(args)?;
    for &levels in &args.subdivide {
        cagerig::memory_estimate::check_fits(
            &format!("bench --subdivide {levels}"),
            cagerig::memory_estimate::subdivided_vertices(
                base.mesh.num_vertices() as u64,
                base.mesh.num_triangles() as u64,
                u32::try_from(levels).unwrap_or(u32::MAX),
            ),
            base.cage.num_vertices() as u64,
        )?;
    }
    if args.coords == cagerig::CoordsKind::Green {
        return run_green(args, &name, &base);
    }
    let mut measured = Vec::new();
    for &levels in &args.subdivide {
        let (model, parts) = model_parts(&name, &base, levels)?;
        if !args.json {
            eprintln!(
                "benchmarking {model} ({} vertices)…",
                parts.mesh.num_vertices()
            );
        }
        let one_thread = if args.skip_one_thread {
            None
        } else {
            Some(one_thread_pool()?.install(|| {
                bench_model(
                    model.clone(),
                    parts.clone(),
                    args.repeat_scale,
                    args.cage_fit,
                )
            })?)
        };
        measured.push((
            bench_model(model, parts, args.repeat_scale, args.cage_fit)?,
            one_thread,
        ));
    }
    // After the models, so that its buffer does not count in their peak memory.
    let bandwidth = crate::bench_bandwidth::read_bandwidth_gbs();
    let bandwidth_one_thread = if args.skip_one_thread {
        None
    } else {
        Some(one_thread_pool()?.install(crate::bench_bandwidth::read_bandwidth_gbs))
    };
    let rows: Vec<ModelReport> = measured
        .into_iter()
        .map(|(row, one_thread)| ModelReport {
            row,
            one_thread,
            read_bandwidth_gbs: bandwidth,
            read_bandwidth_gbs_one_thread: bandwidth_one_thread,
        })
        .collect();
    if args.json {
        println!("{}", serde_json::to_string_pretty(&rows)?);
    } else {
        crate::bench_table::print_table(&rows);
    }
    Ok(())
}

/// The model at `levels` subdivisions of `base` (Λ rows not carried: the bench computes Λ).
fn model_parts(name: &str, base: &RigParts, levels: usize) -> anyhow::Result<(String, RigParts)> {
    if levels == 0 {
        return Ok((name.to_string(), base.clone()));
    }
    let sub =
        cagerig::subdivide::subdivide_rig(&base.mesh, &base.skin_weights, None, None, levels)?;
    Ok((
        format!("{name} N={levels}"),
        RigParts::new(
            sub.mesh,
            base.skeleton.clone(),
            sub.skin_weights,
            base.cage.clone(),
        ),
    ))
}

/// `bench --coords green`: the Green rows of every model ([`crate::bench_green`]).
fn run_green(args: &Args, name: &str, base: &RigParts) -> anyhow::Result<()> {
    let mut rows = Vec::new();
    for &levels in &args.subdivide {
        let (model, parts) = model_parts(name, base, levels)?;
        let nv = parts.mesh.num_vertices();
        if !args.json {
            eprintln!("benchmarking {model} ({nv} vertices, Green coordinates)…");
        }
        let scale = args.repeat_scale;
        rows.push(crate::bench_green::bench_green_model(
            model,
            parts,
            args.cage_fit,
            |base| reps(base, scale, nv),
        )?);
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&rows)?);
    } else {
        crate::bench_green::print_green_table(&rows);
    }
    Ok(())
}

/// The pool of the "1 thread" pass (like for like with the single-threaded paper tool).
fn one_thread_pool() -> anyhow::Result<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .context("building a one-thread pool")
}

fn reps(base: usize, scale: f64, vertices: usize) -> usize {
    // Fewer repetitions of the heavy steps on big meshes.
    let factor = if vertices > 50_000 {
        0.3
    } else if vertices > 10_000 {
        0.6
    } else {
        1.0
    };
    ((base as f64 * scale * factor).round() as usize).max(3)
}

fn bench_model(
    model: String,
    parts: RigParts,
    scale: f64,
    cage_fit: cagerig::CageFitKind,
) -> anyhow::Result<ModelRow> {
    // Reset the peak-RSS counter (VmHWM) so the figure is this model's, not the process's.
    let _ = std::fs::write("/proc/self/clear_refs", "5");
    let nv = parts.mesh.num_vertices();
    let nj = parts.skeleton.len();
    let nc = parts.cage.num_vertices();
    let (cage, _) = cagerig::cage_enclosure::validate_cage_for_mesh(
        parts.cage.clone(),
        &parts.mesh.positions,
        false,
    )?;

    let mut phi = None;
    let mvc_stat = time(reps(5, scale, nv), 1, || {
        drop(phi.take()); // one Φ alive at a time
        phi = Some(mvc::compute_cage_coords(&cage, &parts.mesh.positions, None));
    });
    let phi = phi
        .context("no timing run")?
        .context("computing mean value coordinates")?;

    let mut selection = None;
    let maxvol_stat = time(reps(5, scale, nv), 1, || {
        selection = Some(maxvol::select_maxvol_rows(&phi));
    });
    let rows = selection
        .context("no timing run")?
        .context("MaxVol selection")?
        .rows;
    let maxvol_log_abs_det =
        maxvol::log_abs_det_of_rows(&phi, &rows).context("ln |det| of the MaxVol rows")?;

    let mut skelup = None;
    let skelup_stat = time(reps(5, scale, nv), 1, || {
        skelup = Some(SkeletonUpdater::new(
            &parts.mesh,
            &parts.skeleton,
            &parts.skin_weights,
            &phi,
            None,
            &cage.positions,
            JointLocalisation::default(),
        ));
    });
    let (skelup, _) = skelup
        .context("no timing run")?
        .context("skeleton updater")?;

    let cageup_stat = time(reps(21, scale, nv), 2, || {
        let _ = CageUpdater::new(&phi, rows.clone(), CageFitMode::Interpolate);
    });

    // CoR centres as the session computes them when none are loaded: Λ (Eq. 14) directly.
    let mut lambda = None;
    let cor_centres_stat = time(if nv > 20_000 { 1 } else { 3 }, 0, || {
        lambda = Some(cagerig::session::compute_centre_coords(
            &parts.mesh.positions,
            &parts.mesh.triangles,
            &parts.skin_weights,
            &phi,
            &cagerig::skinning::CorCentresOptions::default(),
        ));
    });
    let lambda = lambda.context("no timing run")?.context("CoR centres")?;
    let cor_centres_method = cagerig::session::centre_coords_method(nv).to_string();

    // The session, from the precomputed parts (Φ moved in, not copied).
    let joint_coords: Vec<Vec<f64>> = (0..nj).map(|j| skelup.joint_row(j).to_vec()).collect();
    let base_parts = RigParts::new(
        parts.mesh.clone(),
        parts.skeleton.clone(),
        parts.skin_weights.clone(),
        parts.cage.clone(),
    );
    let session_parts = RigParts {
        cage_coords: Some(phi),
        maxvol_rows: Some(rows.clone()),
        cor_rows: None,
        joint_coords: Some(joint_coords.clone()),
        cor_centre_coords: Some(lambda),
        ..parts
    };
    let session_options = SessionOptions {
        cage_fit,
        ..SessionOptions::default()
    };
    let (mut session, _) = RigSession::new(session_parts, session_options)?;
    let cage_fit_used = session.cage_fit();
    let parts_weights = session.skin_weights().clone();
    // The pose of the paper tool's per-frame timings: one joint bent by 60° about +X.
    let bend_joint = session.skeleton().find("lowerarm01.R").unwrap_or(nj / 2);
    session.rotate_joint(bend_joint, DVec3::X, 60f64.to_radians())?;

    let refactor_stat = time(reps(51, scale, nv), 3, || {
        let _ = session.refactor_reverser();
    });

    let transforms: Vec<DAffine3> = session.posed_from_rest().to_vec();
    let rest = session.rest_mesh().to_vec();
    let mut out = vec![DVec3::ZERO; nv];
    let frame_reps = reps(200, scale, nv);
    let nnz = parts_weights.num_entries() as u64;
    let skin_bytes = nv as u64 * (24 + 24 + 4) + nnz * 12;

    let lbs = LinearBlendSkinning::new(&parts_weights);
    let lbs_stat =
        time(frame_reps, 5, || lbs.apply(&transforms, &rest, &mut out)).with_bytes(skin_bytes);
    let dqs = DualQuaternionSkinning::new(&parts_weights);
    let mut dqs_scratch = DqsScratch::new(nj);
    let dqs_stat = time(frame_reps, 5, || {
        dqs.apply(&transforms, &rest, &mut dqs_scratch, &mut out)
    })
    .with_bytes(skin_bytes + nv as u64 * 4);
    session.set_skinning(cagerig::skinning::SkinningMethod::Cor)?;
    let centres = session
        .cor_centres()
        .map(<[DVec3]>::to_vec)
        .unwrap_or_default();
    session.set_skinning(cagerig::skinning::SkinningMethod::Lbs)?;
    let cor = CorSkinning::new(&parts_weights);
    let mut cor_scratch = CorScratch::new(nj);
    let cor_stat = time(frame_reps, 5, || {
        cor.apply(&transforms, &rest, &centres, &mut cor_scratch, &mut out)
    })
    .with_bytes(skin_bytes + nv as u64 * (24 + 4));

    // The f32 per-frame kernels (error vs f64 stated in their tests: ≤ 2e-6 of the bbox diagonal).
    let mut out32 = vec![glam::Vec3::ZERO; nv];
    let lbs32 = LbsF32::new(&parts_weights, &rest)?;
    let mut lbs32_scratch = LbsF32Scratch::new(nj);
    let f32_bytes = nv as u64 * (12 + 12 + 4) + nnz * 6;
    let lbs32_stat = time(frame_reps, 5, || {
        lbs32.apply(&transforms, &mut lbs32_scratch, &mut out32)
    })
    .with_bytes(f32_bytes);
    let dqs32 = DqsF32::new(&parts_weights, &rest)?;
    let mut dqs32_scratch = DqsF32Scratch::new(nj);
    let dqs32_stat = time(frame_reps, 5, || {
        dqs32.apply(&transforms, &mut dqs32_scratch, &mut out32)
    })
    .with_bytes(f32_bytes);
    let cor32 = CorF32::new(&parts_weights, &rest, &centres)?;
    let mut cor32_scratch = CorF32Scratch::new(nj);
    let cor32_stat = time(frame_reps, 5, || {
        cor32.apply(&transforms, &mut cor32_scratch, &mut out32)
    })
    .with_bytes(f32_bytes + nv as u64 * 12);

    // Animation frame: skeleton keys (rotations) and cage keys (rest-cage offsets), async.
    let (skeleton_track, cage_track) = synthetic_tracks(&session)?;
    let mut player = AnimationPlayer::new(&session, Some(skeleton_track), Some(cage_track))?;
    let duration = player.duration();
    let mut frame = 0usize;
    let anim_stat = time(frame_reps, 5, || {
        frame += 1;
        let t = (frame as f64 * 0.037) % duration;
        let _ = player.apply(t, &mut session);
    })
    // Cage keys are cached as ΦC_k: a frame lerps two meshes (2 reads, 1 write) then skins.
    .with_bytes(skin_bytes + nv as u64 * 72);
    let animation_cage_quality = animation_cage_quality(&mut player, &mut session, duration)?;
    session.reset_pose();
    session.rotate_joint(bend_joint, DVec3::X, 60f64.to_radians())?;

    let (drag_stat, grab_stat) = bench_cage_events(
        &mut session,
        bend_joint,
        frame_reps,
        reps(51, scale, nv),
        skin_bytes,
        [8, 8],
    )?;
    session.set_display_precision(DisplayPrecision::F32)?;
    let (drag_display_stat, grab_display_stat) = bench_cage_events(
        &mut session,
        bend_joint,
        frame_reps,
        reps(51, scale, nv),
        f32_bytes,
        [8, 4],
    )?;
    session.set_display_precision(DisplayPrecision::Exact)?;

    // The same cage events with Φ rounded to f32 (`CoordsPrecision::F32`): a second session
    // from the base parts (Φ recomputed, MaxVol rows and Ψ reused), built after the f64 one
    // is dropped so the two never coexist in memory.
    drop(player);
    drop(session);
    let f32_parts = RigParts {
        cage_coords: None,
        maxvol_rows: Some(rows),
        cor_rows: None,
        joint_coords: Some(joint_coords),
        cor_centre_coords: None,
        ..base_parts
    };
    let f32_options = SessionOptions {
        cage_coords_precision: CoordsPrecision::F32,
        cage_fit,
        ..SessionOptions::default()
    };
    let (mut session32, _) = RigSession::new(f32_parts, f32_options)?;
    session32.rotate_joint(bend_joint, DVec3::X, 60f64.to_radians())?;
    let (drag32_stat, grab32_stat) = bench_cage_events(
        &mut session32,
        bend_joint,
        frame_reps,
        reps(51, scale, nv),
        skin_bytes,
        [4, 4],
    )?;

    Ok(ModelRow {
        model,
        vertices: nv,
        joints: nj,
        cage_vertices: nc,
        peak_memory_mb: peak_memory_mb(),
        precision: "f64",
        mvc: mvc_stat,
        maxvol: maxvol_stat,
        maxvol_log_abs_det,
        skelup_preprocess: skelup_stat,
        cageup_preprocess: cageup_stat,
        cor_centres: cor_centres_stat,
        cor_centres_method,
        cagerev_refactor: refactor_stat,
        lbs: lbs_stat,
        dqs: dqs_stat,
        cor: cor_stat,
        animation_frame: anim_stat,
        cage_fit: cage_fit_used,
        animation_cage_quality,
        rest_cage_drag: drag_stat,
        grab_after_skeleton_edit: grab_stat,
        rest_cage_drag_f32_coords: drag32_stat,
        grab_after_skeleton_edit_f32_coords: grab32_stat,
        rest_cage_drag_display: drag_display_stat,
        grab_after_skeleton_edit_display: grab_display_stat,
        lbs_f32: lbs32_stat,
        dqs_f32: dqs32_stat,
        cor_f32: cor32_stat,
    })
}

/// The worst cage quality over 20 evenly spaced frames of the animation `player` (of length
/// `duration`) on `session`; frames the rig refuses are skipped. `None` when every frame was.
fn animation_cage_quality(
    player: &mut AnimationPlayer,
    session: &mut RigSession,
    duration: f64,
) -> anyhow::Result<Option<cagerig::cage_quality::CageQuality>> {
    let probe = cagerig::cage_quality::CageQualityProbe::of_session(session)?;
    let mut worst: Option<cagerig::cage_quality::CageQuality> = None;
    for i in 0..20 {
        let t = duration * i as f64 / 20.0;
        if player.apply(t, session).is_ok() {
            let q = probe.measure_session(session);
            worst = Some(worst.map_or(q, |w| w.worst(q)));
        }
    }
    Ok(worst)
}
