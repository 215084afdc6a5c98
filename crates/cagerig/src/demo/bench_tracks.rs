//! The synthetic animation `cagerig bench` plays (and the examples that split its frames): a
//! 5-key skeleton track bending every joint a little about alternating axes, and a 3-key cage
//! track breathing the rest cage about its centre, with unrelated key times (asynchronous
//! tracks).

use glam::{DAffine3, DQuat, DVec3};

use crate::animation::{AnimationError, CageTrack, SkeletonTrack};
use crate::skeleton::Skeleton;

/// The bench's tracks for `skeleton` and the rest cage `rest_cage` (`#C`): joint j turns by
/// 0.2·k rad at key k (times 0, 3, 6.5, 9, 10 s) about X, Y or Z in turn; the cage keys
/// (times 0, 1.5, 3 s) scale it by 1 + 0.05·k about its bounding box's centre.
pub fn synthetic_tracks(
    skeleton: &Skeleton,
    rest_cage: &[DVec3],
) -> Result<(SkeletonTrack, CageTrack), AnimationError> {
    let rest = skeleton.rest_world_from_joint();
    let mut rest_locals = vec![DAffine3::IDENTITY; skeleton.len()];
    skeleton.locals_from_worlds(&rest, &mut rest_locals);
    let times = vec![0.0, 3.0, 6.5, 9.0, 10.0];
    let keys = (0..times.len())
        .map(|k| {
            rest_locals
                .iter()
                .enumerate()
                .map(|(j, l)| {
                    let axis = [DVec3::X, DVec3::Y, DVec3::Z][(j + k) % 3];
                    *l * DAffine3::from_quat(DQuat::from_axis_angle(axis, 0.2 * k as f64))
                })
                .collect()
        })
        .collect();
    let (lo, hi) = crate::mesh::bounding_box(rest_cage);
    let centre = (lo + hi) * 0.5;
    let cage_times = vec![0.0, 1.5, 3.0];
    let offsets = (0..cage_times.len())
        .map(|k| {
            rest_cage
                .iter()
                .map(|c| (*c - centre) * 0.05 * k as f64)
                .collect()
        })
        .collect();
    Ok((
        SkeletonTrack::new(times, keys)?,
        CageTrack::new(cage_times, offsets)?,
    ))
}
