//! The cage events and animation tracks `cagerig bench` times: a rest-cage drag near the bent
//! joint, grabs right after skeleton edits, and synthetic asynchronous skeleton and cage tracks.

use std::time::Instant;

use cagerig::session::RigSession;
use glam::DVec3;

use crate::bench_report::{Stat, time};

/// A rest-cage drag of the 5 cage vertices nearest `bend_joint` (`drag_reps` events), then
/// `grab_reps` current-cage grabs each right after a small skeleton edit (refactor + solve +
/// full chain). `phi_bytes` is the size of one coordinate the drag and the grab read (8 for
/// f64, 4 for f32).
pub(crate) fn bench_cage_events(
    session: &mut RigSession,
    bend_joint: usize,
    drag_reps: usize,
    grab_reps: usize,
    skin_bytes: u64,
    [drag_phi_bytes, grab_phi_bytes]: [usize; 2],
) -> anyhow::Result<(Stat, Stat)> {
    let (nv, nc) = (session.rest_mesh().len(), session.rest_cage().len());
    let joint_pos = session.rest_world_from_joint()[bend_joint].translation;
    let mut by_distance: Vec<usize> = (0..nc).collect();
    by_distance.sort_by(|&a, &b| {
        session.rest_cage()[a]
            .distance(joint_pos)
            .total_cmp(&session.rest_cage()[b].distance(joint_pos))
    });
    let drag: Vec<usize> = by_distance[..5.min(nc)].to_vec();
    let step = 1e-3 * {
        let (lo, hi) = cagerig::mesh::bounding_box(session.rest_cage());
        (hi - lo).length()
    };
    let mut sign = 1.0;
    let drag_stat = time(drag_reps, 5, || {
        sign = -sign;
        let _ = session.move_rest_cage(&drag, &[DVec3::new(sign * step, 0.0, 0.0)]);
    })
    .with_bytes(skin_bytes + (nv * drag.len() * drag_phi_bytes) as u64 + nv as u64 * 48);

    let mut samples = Vec::with_capacity(grab_reps);
    for i in 0..grab_reps + 3 {
        let angle = if i % 2 == 0 { 0.01 } else { -0.01 };
        session.rotate_joint(bend_joint, DVec3::Y, angle)?;
        let t = Instant::now();
        session.move_posed_cage(&drag[..1], &[DVec3::new(0.0, sign * step, 0.0)])?;
        let ms = t.elapsed().as_secs_f64() * 1e3;
        sign = -sign;
        if i >= 3 {
            samples.push(ms);
        }
    }
    samples.sort_by(f64::total_cmp);
    let grab_stat = Stat {
        median_ms: samples[samples.len() / 2],
        min_ms: samples[0],
        max_ms: samples[samples.len() - 1],
        bytes_moved: Some(skin_bytes + (nv * nc * grab_phi_bytes) as u64 + nv as u64 * 48),
    };
    Ok((drag_stat, grab_stat))
}

/// The bench's synthetic tracks ([`cagerig::demo::bench_tracks::synthetic_tracks`]) for the
/// session's skeleton and rest cage.
pub(crate) fn synthetic_tracks(
    session: &RigSession,
) -> anyhow::Result<(
    cagerig::animation::SkeletonTrack,
    cagerig::animation::CageTrack,
)> {
    Ok(cagerig::demo::bench_tracks::synthetic_tracks(
        session.skeleton(),
        session.rest_cage(),
    )?)
}
