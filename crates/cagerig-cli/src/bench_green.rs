//! `cagerig bench --coords green`: the session-level rows of the bench for a rig bound with
//! Green coordinates — binding (against mean value coordinates on the same mesh), session
//! assembly, the per-event rows (animation frame, rest-cage drag, grab after a skeleton edit) —
//! and the Newton iterations each event took (CageUp's Levenberg–Marquardt steps and Hessians,
//! CageRev's Newton steps). The skinning kernels do not depend on the coordinates and are
//! benched by the MVC pass.

use std::time::Instant;

use anyhow::Context;
use cagerig::CoordsKind;
use cagerig::coords::{green, mvc};
use cagerig::playback::AnimationPlayer;
use cagerig::session::{DisplayPrecision, RigParts, RigSession, SessionOptions};
use glam::DVec3;
use serde::Serialize;

use crate::bench_report::Stat;

/// Newton work per event: medians and maxima over the events of a row.
#[derive(Debug, Clone, Copy, Serialize)]
pub(crate) struct IterationStat {
    /// CageUp steps (each with one Hessian) per event.
    pub cageup_median: usize,
    pub cageup_max: usize,
    /// CageRev Newton steps per grab (0 for events without a grab).
    pub cagerev_median: usize,
    pub cagerev_max: usize,
}

/// One model's Green figures.
#[derive(Debug, Serialize)]
pub(crate) struct GreenModelRow {
    pub model: String,
    pub coords: &'static str,
    /// CageUp's fit in both sessions (`--cage-fit`).
    pub cage_fit: cagerig::CageFitKind,
    pub vertices: usize,
    pub joints: usize,
    pub cage_vertices: usize,
    pub cage_faces: usize,
    pub peak_memory_mb: f64,
    /// Green coordinates (φ, ψ) of every mesh vertex.
    pub binding: Stat,
    /// Mean value coordinates of the same vertices, for the ratio.
    pub mvc_binding: Stat,
    pub binding_over_mvc: f64,
    /// `RigSession::new` with Green coordinates (binding, MaxVol rows of [φ ψ], Ψ, the fit).
    pub session_build: Stat,
    /// The per-event rows on the exact path (every structure in f64).
    #[serde(flatten)]
    pub exact: GreenEventRows,
    /// The same events on the f32 display path (`DisplayPrecision::F32`: the drawn M and M' in
    /// f32 within 2e-6 of the diagonal; C, C', S, S' and CageUp's rows exact).
    pub display_f32: GreenEventRows,
    /// Events refused (Green CageUp fold) among the timed ones.
    pub refused_events: usize,
    /// The same events on a mean value rig of the same model, timed in the same run (exact
    /// path), for the ratios.
    pub mvc_exact: GreenEventRows,
    /// Green / MVC medians of the animation frame and the rest-cage drag (exact path).
    pub frame_over_mvc: f64,
    pub drag_over_mvc: f64,
    /// Green / MVC of the bytes the rest-cage drag must move: per vertex, the columns it reads
    /// (the moved cage vertices' of φ or Φ, and for Green ψ's of every face touching them, in
    /// f64), the skin weights, M read and written by the edit and read by the skinning, and M'
    /// written. The two drags run at the same share of the bandwidth when
    /// [`Self::drag_over_mvc`] equals it.
    pub drag_bytes_over_mvc: f64,
    /// The grab after a skeleton edit against its memory-bandwidth bound: the bytes the event
    /// must read (the whole coordinate matrix, [φ ψ] for Green and Φ for MVC, in f64, and the
    /// skin weights that skin M into M') over the read bandwidth measured in this run.
    pub grab_bound: GrabBound,
}

/// A grab's time against the bound set by the bytes it must read, for both kinds.
#[derive(Debug, Serialize)]
pub(crate) struct GrabBound {
    pub read_bandwidth_gbs: f64,
    pub green: KindGrabBound,
    pub mvc: KindGrabBound,
}

/// One kind's grab against its read bound, and the rest-skin product M(C) alone against the
/// bound of its own bytes (the coordinates): the part of the grab no refactorisation, solve or
/// skinning adds to, so the floor the grab's ratio can reach on this host in this run.
#[derive(Debug, Serialize)]
pub(crate) struct KindGrabBound {
    /// The grab's bytes: the coordinates in f64 and the skin weights.
    pub bytes: f64,
    pub bound_ms: f64,
    /// Median grab over the bound.
    pub over_bound: f64,
    /// Fastest grab over the bound.
    pub best_over_bound: f64,
    /// The coordinates' bytes (what M(C) reads).
    pub product_bytes: f64,
    /// Median M(C) over the bound of its bytes.
    pub product_over_bound: f64,
    /// Fastest M(C) over the bound of its bytes.
    pub product_best_over_bound: f64,
}

impl KindGrabBound {
    /// `grab` and `product` (M(C) alone) against `product_bytes` + `skin_bytes` and
    /// `product_bytes` at `read_bandwidth_gbs`.
    fn new(
        grab: &Stat,
        product: &Stat,
        product_bytes: f64,
        skin_bytes: f64,
        read_bandwidth_gbs: f64,
    ) -> Self {
        let bound_ms =
            |bytes: f64| (bytes / (read_bandwidth_gbs * 1e9) * 1e3).max(f64::MIN_POSITIVE);
        let bytes = product_bytes + skin_bytes;
        Self {
            bytes,
            bound_ms: bound_ms(bytes),
            over_bound: grab.median_ms / bound_ms(bytes),
            best_over_bound: grab.min_ms / bound_ms(bytes),
            product_bytes,
            product_over_bound: product.median_ms / bound_ms(product_bytes),
            product_best_over_bound: product.min_ms / bound_ms(product_bytes),
        }
    }
}

/// The per-event rows of one display precision, with their Newton steps.
#[derive(Debug, Serialize)]
pub(crate) struct GreenEventRows {
    pub animation_frame: Stat,
    pub animation_frame_iterations: IterationStat,
    pub rest_cage_drag: Stat,
    pub rest_cage_drag_iterations: IterationStat,
    /// The coordinate columns the drag reads: its moved cage vertices, and for a Green rig the
    /// faces touching them.
    pub rest_cage_drag_columns: usize,
    pub grab_after_skeleton_edit: Stat,
    pub grab_after_skeleton_edit_iterations: IterationStat,
    /// The rest skin M(C) = ΦC (+ ψ·g(C)) alone at the grab's rest cage, the product every
    /// grab makes.
    pub rest_skin_product: Stat,
    /// Events of these rows refused (Green CageUp fold), not timed.
    pub refused: usize,
    /// How far the joint of the drag and grab rows was bent about +X, in degrees: the MVC
    /// pass's 60° in 10° steps, or less where a Green cage folds first (the last step refused).
    pub bend_degrees: f64,
}

/// Whether an edit was applied (`Ok(true)`) or refused because a Green cage cannot follow it
/// (`Ok(false)`, counted in `refused`); any other error stops the bench with `what`.
fn applied(
    result: Result<(), cagerig::RigError>,
    refused: &mut usize,
    what: &'static str,
) -> anyhow::Result<bool> {
    match result {
        Ok(()) => Ok(true),
        Err(
            cagerig::RigError::GreenFitFailed { .. } | cagerig::RigError::GreenGrabFailed { .. },
        ) => {
            *refused += 1;
            Ok(false)
        }
        Err(e) => Err(e).context(what),
    }
}

/// Median/min/max of samples in ms.
fn stat(mut samples: Vec<f64>) -> Stat {
    samples.sort_by(f64::total_cmp);
    let n = samples.len().max(1);
    Stat {
        median_ms: samples.get(n / 2).copied().unwrap_or(0.0),
        min_ms: samples.first().copied().unwrap_or(0.0),
        max_ms: samples.last().copied().unwrap_or(0.0),
        bytes_moved: None,
    }
}

fn iterations(mut cageup: Vec<usize>, mut cagerev: Vec<usize>) -> IterationStat {
    cageup.sort_unstable();
    cagerev.sort_unstable();
    IterationStat {
        cageup_median: cageup.get(cageup.len() / 2).copied().unwrap_or(0),
        cageup_max: cageup.last().copied().unwrap_or(0),
        cagerev_median: cagerev.get(cagerev.len() / 2).copied().unwrap_or(0),
        cagerev_max: cagerev.last().copied().unwrap_or(0),
    }
}

/// Times `event` `reps` times on `session` (after `warmup` untimed runs), with the Newton
/// iterations of each; a refused event (Green fold) is counted, not timed.
fn timed_events(
    session: &mut RigSession,
    reps: usize,
    warmup: usize,
    refused: &mut usize,
    mut event: impl FnMut(&mut RigSession, usize) -> Result<(), cagerig::RigError>,
) -> anyhow::Result<(Stat, IterationStat)> {
    let (mut times, mut up, mut rev) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..reps + warmup {
        let before = session.green_newton_reports().map(|(_, r)| r);
        let start = Instant::now();
        let result = event(session, i);
        let ms = start.elapsed().as_secs_f64() * 1e3;
        if !applied(result, refused, "a benched event")? || i < warmup {
            continue;
        }
        times.push(ms);
        if let Some((fit, reverse)) = session.green_newton_reports() {
            up.push(fit.iterations);
            rev.push(if Some(reverse) == before {
                0
            } else {
                reverse.iterations
            });
        }
    }
    Ok((stat(times), iterations(up, rev)))
}

/// The Green rows of one model.
pub(crate) fn bench_green_model(
    model: String,
    parts: RigParts,
    cage_fit: cagerig::CageFitKind,
    reps: impl Fn(usize) -> usize,
) -> anyhow::Result<GreenModelRow> {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
    let nv = parts.mesh.num_vertices();
    let (cage, _) = cagerig::cage_enclosure::validate_cage_for_mesh(
        parts.cage.clone(),
        &parts.mesh.positions,
        false,
    )?;
    let time = |n: usize, f: &mut dyn FnMut() -> anyhow::Result<()>| -> anyhow::Result<Stat> {
        let mut samples = Vec::with_capacity(n);
        for _ in 0..n {
            let start = Instant::now();
            f()?;
            samples.push(start.elapsed().as_secs_f64() * 1e3);
        }
        Ok(stat(samples))
    };
    // The coordinates of each kind for the whole mesh, results dropped.
    type Coordinates = fn(&cagerig::TriMesh, &[DVec3]) -> Result<(), cagerig::RigError>;
    let time_coordinates =
        |compute: Coordinates| time(reps(5), &mut || Ok(compute(&cage, &parts.mesh.positions)?));
    let binding = time_coordinates(|c, p| green::compute_green_coords(c, p, None).map(drop))?;
    let mvc_binding = time_coordinates(|c, p| mvc::compute_cage_coords(c, p, None).map(drop))?;
    let options = SessionOptions {
        coords: CoordsKind::Green,
        cage_fit,
        ..SessionOptions::default()
    };
    let mut built = None;
    let session_build = time(reps(3).min(3), &mut || {
        built = None;
        built = Some(RigSession::new(parts.clone(), options.clone())?.0);
        Ok(())
    })?;
    let mut session = built.context("no timing run")?;
    let nj = session.skeleton().len();
    let nc = session.rest_cage().len();
    let cage_faces = session.green_triangles().map_or(0, <[[u32; 3]]>::len);
    let bend_joint = session.skeleton().find("lowerarm01.R").unwrap_or(nj / 2);
    // The same synthetic tracks on both paths (made before any edit moves the rest cage).
    let tracks = crate::bench_events::synthetic_tracks(&session)?;
    let exact = event_rows(&mut session, bend_joint, &tracks, &reps)?;
    session.set_display_precision(DisplayPrecision::F32)?;
    let display_f32 = event_rows(&mut session, bend_joint, &tracks, &reps)?;
    drop(session);
    // The same events on a mean value rig of the same model, in the same run.
    let mvc_options = SessionOptions {
        cage_fit,
        ..SessionOptions::default()
    };
    let mut mvc_session = RigSession::new(parts.clone(), mvc_options)?.0;
    let mvc_exact = event_rows(&mut mvc_session, bend_joint, &tracks, &reps)?;
    drop(mvc_session);
    let read_bandwidth_gbs = crate::bench_bandwidth::read_bandwidth_gbs();
    let matrix_bytes = |columns: usize| 8.0 * nv as f64 * columns as f64;
    let ratio = |a: &Stat, b: &Stat| a.median_ms / b.median_ms.max(f64::MIN_POSITIVE);
    // The skinning of M into M' reads the weights too: per vertex its row start (u32), per
    // entry its joint (u16) and weight (f64), as `LinearBlendSkinning` stores them.
    let skin_bytes = 4.0 * nv as f64 + 10.0 * parts.skin_weights.num_entries() as f64;
    let grab_bound = GrabBound {
        read_bandwidth_gbs,
        green: KindGrabBound::new(
            &exact.grab_after_skeleton_edit,
            &exact.rest_skin_product,
            matrix_bytes(nc + cage_faces),
            skin_bytes,
            read_bandwidth_gbs,
        ),
        mvc: KindGrabBound::new(
            &mvc_exact.grab_after_skeleton_edit,
            &mvc_exact.rest_skin_product,
            matrix_bytes(nc),
            skin_bytes,
            read_bandwidth_gbs,
        ),
    };
    Ok(GreenModelRow {
        model,
        coords: CoordsKind::Green.name(),
        cage_fit,
        vertices: nv,
        joints: nj,
        cage_vertices: nc,
        cage_faces,
        peak_memory_mb: crate::bench_report::peak_memory_mb(),
        binding_over_mvc: binding.median_ms / mvc_binding.median_ms.max(f64::MIN_POSITIVE),
        binding,
        mvc_binding,
        session_build,
        refused_events: exact.refused + display_f32.refused,
        frame_over_mvc: ratio(&exact.animation_frame, &mvc_exact.animation_frame),
        drag_over_mvc: ratio(&exact.rest_cage_drag, &mvc_exact.rest_cage_drag),
        drag_bytes_over_mvc: {
            // M read and written by the delta, read again by the skin, and M' written.
            let drag_bytes = |columns: usize| matrix_bytes(columns) + skin_bytes + 96.0 * nv as f64;
            drag_bytes(exact.rest_cage_drag_columns) / drag_bytes(mvc_exact.rest_cage_drag_columns)
        },
        grab_bound,
        exact,
        display_f32,
        mvc_exact,
    })
}

/// The per-event rows on `session` at its display precision: animation frames of the synthetic
/// tracks, a rest-cage drag and a grab after a skeleton edit near `bend_joint`.
fn event_rows(
    session: &mut RigSession,
    bend_joint: usize,
    (skeleton_track, cage_track): &(
        cagerig::animation::SkeletonTrack,
        cagerig::animation::CageTrack,
    ),
    reps: &impl Fn(usize) -> usize,
) -> anyhow::Result<GreenEventRows> {
    let nc = session.rest_cage().len();
    let mut refused = 0;
    let refused = &mut refused;
    session.reset_pose();

    // Animation: the bench's synthetic tracks (skeleton keys and breathing cage keys).
    let mut player = AnimationPlayer::new(
        session,
        Some(skeleton_track.clone()),
        Some(cage_track.clone()),
    )?;
    let duration = player.duration();
    let (animation_frame, animation_frame_iterations) =
        timed_events(session, reps(100), 3, refused, |s, i| {
            player.apply((i as f64 * 0.037) % duration, s)
        })?;
    drop(player);
    session.reset_pose();
    // The MVC pass's pose (the joint bent by 60° about +X), reached in 10° steps: a Green
    // CageUp follows a large bend better in steps (docs/green-coordinates.md). Where a step
    // folds the cage (the built-in snake's), the rows are timed at the last pose reached.
    let mut bend_degrees = 0.0;
    for _ in 0..6 {
        let step = session.rotate_joint(bend_joint, DVec3::X, 10f64.to_radians());
        if !applied(step, refused, "bending the benched joint")? {
            break;
        }
        bend_degrees += 10.0;
    }

    // The rest-cage drag of the 5 cage vertices nearest the bent joint, back and forth.
    let joint = session.rest_world_from_joint()[bend_joint].translation;
    let mut by_distance: Vec<usize> = (0..nc).collect();
    by_distance.sort_by(|&a, &b| {
        session.rest_cage()[a]
            .distance(joint)
            .total_cmp(&session.rest_cage()[b].distance(joint))
    });
    let drag: Vec<usize> = by_distance[..5.min(nc)].to_vec();
    let step = 1e-3 * {
        let (lo, hi) = cagerig::mesh::bounding_box(session.rest_cage());
        (hi - lo).length()
    };
    let touched_faces = session.green_triangles().map_or(0, |triangles| {
        let touches = |t: &[u32; 3]| t.iter().any(|&v| drag.contains(&(v as usize)));
        triangles.iter().filter(|t| touches(t)).count()
    });
    let rest_cage_drag_columns = drag.len() + touched_faces;
    let (rest_cage_drag, rest_cage_drag_iterations) =
        timed_events(session, reps(100), 3, refused, |s, i| {
            let sign = if i % 2 == 0 { 1.0 } else { -1.0 };
            s.move_rest_cage(&drag, &[DVec3::new(sign * step, 0.0, 0.0)])
        })?;

    // A grab right after a small skeleton edit (the edit untimed, as in the MVC pass).
    let (mut times, mut up, mut rev) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..reps(51) + 3 {
        let angle = if i % 2 == 0 { 0.01 } else { -0.01 };
        let edit = session.rotate_joint(bend_joint, DVec3::Y, angle);
        if !applied(edit, refused, "the skeleton edit before a benched grab")? {
            continue;
        }
        let sign = if i % 2 == 0 { 1.0 } else { -1.0 };
        let start = Instant::now();
        let grab = session.move_posed_cage(&drag[..1], &[DVec3::new(0.0, sign * step, 0.0)]);
        if !applied(grab, refused, "a benched grab")? {
            continue;
        }
        let ms = start.elapsed().as_secs_f64() * 1e3;
        if i >= 3 {
            times.push(ms);
            if let Some((fit, reverse)) = session.green_newton_reports() {
                up.push(fit.iterations);
                rev.push(reverse.iterations);
            }
        }
    }
    // The rest skin M(C) alone, the product each grab makes, into a buffer of the bench's.
    let mut rest_skin = vec![DVec3::ZERO; session.rest_mesh().len()];
    let mut product_error = None;
    let rest_skin_product = crate::bench_report::time(reps(51), 3, || {
        if let Err(e) = session.rest_mesh_for_cage(session.rest_cage(), &mut rest_skin) {
            product_error.get_or_insert(e);
        }
    });
    if let Some(e) = product_error {
        return Err(e.into());
    }
    Ok(GreenEventRows {
        animation_frame,
        animation_frame_iterations,
        rest_cage_drag,
        rest_cage_drag_iterations,
        rest_cage_drag_columns,
        grab_after_skeleton_edit: stat(times),
        grab_after_skeleton_edit_iterations: iterations(up, rev),
        rest_skin_product,
        refused: *refused,
        bend_degrees,
    })
}

/// The table of `bench --coords green`.
pub(crate) fn print_green_table(rows: &[GreenModelRow]) {
    for row in rows {
        println!(
            "\n{} (Green coordinates, {} cage fit): {} vertices, {} joints, cage {} vertices / {} faces, peak {:.0} MB",
            row.model,
            row.cage_fit,
            row.vertices,
            row.joints,
            row.cage_vertices,
            row.cage_faces,
            row.peak_memory_mb
        );
        println!(
            "{:<26} {:>10} {:>10} {:>10}   Newton steps per event (CageUp, CageRev): median / max",
            "row", "median ms", "min ms", "max ms"
        );
        let line = |name: &str, s: &Stat, it: Option<&IterationStat>| {
            let steps = it.map_or(String::new(), |i| {
                format!(
                    "   {} / {}, {} / {}",
                    i.cageup_median, i.cageup_max, i.cagerev_median, i.cagerev_max
                )
            });
            println!(
                "{name:<26} {:>10.3} {:>10.3} {:>10.3}{steps}",
                s.median_ms, s.min_ms, s.max_ms
            );
        };
        line("binding (Green)", &row.binding, None);
        line("binding (MVC)", &row.mvc_binding, None);
        println!(
            "{:<26} {:>10.2}×",
            "binding Green / MVC", row.binding_over_mvc
        );
        line("session build", &row.session_build, None);
        for (precision, events) in [("", &row.exact), (" (f32 display)", &row.display_f32)] {
            line(
                &format!("animation frame{precision}"),
                &events.animation_frame,
                Some(&events.animation_frame_iterations),
            );
            line(
                &format!("rest-cage drag{precision}"),
                &events.rest_cage_drag,
                Some(&events.rest_cage_drag_iterations),
            );
            line(
                &format!("grab after skel. edit{precision}"),
                &events.grab_after_skeleton_edit,
                Some(&events.grab_after_skeleton_edit_iterations),
            );
        }
        let mvc = &row.mvc_exact;
        line("animation frame (MVC)", &mvc.animation_frame, None);
        line("rest-cage drag (MVC)", &mvc.rest_cage_drag, None);
        line(
            "grab after skel. edit (MVC)",
            &mvc.grab_after_skeleton_edit,
            None,
        );
        println!(
            "{:<26} {:>10.2}×   (medians, exact path, this run)",
            "animation frame Green/MVC", row.frame_over_mvc
        );
        println!(
            "{:<26} {:>10.2}×",
            "rest-cage drag Green/MVC", row.drag_over_mvc
        );
        println!(
            "{:<26} {:>10.2}×   (bytes the drags must move: columns read, skin weights, M, M')",
            "rest-cage drag bytes", row.drag_bytes_over_mvc
        );
        let b = &row.grab_bound;
        println!(
            "grab against its read bound at {:.1} GB/s, median (fastest): Green {:.0} MB, bound \
             {:.2} ms, {:.2}× it ({:.2}×); MVC {:.0} MB, bound {:.2} ms, {:.2}× it ({:.2}×)",
            b.read_bandwidth_gbs,
            b.green.bytes / 1e6,
            b.green.bound_ms,
            b.green.over_bound,
            b.green.best_over_bound,
            b.mvc.bytes / 1e6,
            b.mvc.bound_ms,
            b.mvc.over_bound,
            b.mvc.best_over_bound,
        );
        println!(
            "M(C) alone against the bound of the coordinates, median (fastest): Green {:.2}× \
             ({:.2}×), MVC {:.2}× ({:.2}×)",
            b.green.product_over_bound,
            b.green.product_best_over_bound,
            b.mvc.product_over_bound,
            b.mvc.product_best_over_bound,
        );
        for (precision, events) in [("exact", &row.exact), ("f32 display", &row.display_f32)] {
            if events.bend_degrees < 60.0 {
                println!(
                    "drag and grab rows ({precision}) at a {:.0}° bend, not 60°: Green CageUp \
                     refused the next 10° step",
                    events.bend_degrees
                );
            }
        }
        if row.refused_events > 0 {
            println!(
                "refused events (Green fold; not timed): {} exact, {} f32 display",
                row.exact.refused, row.display_f32.refused
            );
        }
    }
}
