//! Keyframed animation tracks (pure data + sampling, no IO).
//!
//! Sampling follows the paper tool's AsyncAnimator: before the first keyframe the first is used,
//! after the last the last; otherwise the bracketing keyframes `lo < hi` with
//! `times[lo] < t ≤ times[hi]` are blended with `a = (t − t_lo) / (t_hi − t_lo)`.
//! Skeleton keys are local transforms `parent_from_joint` (roots: `world_from_joint`), blended
//! per joint: translation and scale lerp, rotation slerp along the shorter arc. Cage keys are
//! offsets of the rest cage C from the original rest cage, blended linearly.

use glam::{DAffine3, DQuat, DVec3};
use thiserror::Error;

/// |det| of a keyframe's 3×3 part below which it cannot be decomposed for interpolation.
pub const SINGULAR_DETERMINANT: f64 = 1e-12;

/// A track whose keyframes are inconsistent.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum AnimationError {
    /// The track has no keyframes.
    #[error("the track has no keyframes")]
    Empty,
    /// The number of keyframe times and of keyframes differ.
    #[error("{times} keyframe times but {keyframes} keyframes")]
    LengthMismatch {
        /// Number of keyframe times.
        times: usize,
        /// Number of keyframes.
        keyframes: usize,
    },
    /// A keyframe time is NaN or infinite.
    #[error("keyframe {keyframe} has time {time}: times must be finite")]
    NonFiniteTime {
        /// The 0-based keyframe index.
        keyframe: usize,
        /// Its time, in seconds.
        time: f64,
    },
    /// A keyframe time is not strictly after the previous one.
    #[error(
        "keyframe {keyframe} has time {time}, not after the previous keyframe's {previous}: times must increase strictly"
    )]
    TimeNotIncreasing {
        /// The 0-based keyframe index.
        keyframe: usize,
        /// Its time, in seconds.
        time: f64,
        /// The previous keyframe's time, in seconds.
        previous: f64,
    },
    /// A keyframe has a different number of joints or cage vertices than the first.
    #[error("keyframe {keyframe} has {actual} {what} but the track has {expected}")]
    KeyframeSize {
        /// The 0-based keyframe index.
        keyframe: usize,
        /// What was counted ("joints" or "cage vertices").
        what: &'static str,
        /// The count of the first keyframe (`#J` or `#C`).
        expected: usize,
        /// The count of this keyframe.
        actual: usize,
    },
    /// A joint transform or cage offset of a keyframe is NaN or infinite.
    #[error("keyframe {keyframe}: {what} {index} is not finite")]
    NonFinite {
        /// The 0-based keyframe index.
        keyframe: usize,
        /// What is not finite ("joint transform" or "cage vertex offset").
        what: &'static str,
        /// The joint or cage vertex index.
        index: usize,
    },
    /// A joint transform of a keyframe has |det| ≤ [`SINGULAR_DETERMINANT`] and cannot be
    /// decomposed into scale, rotation and translation.
    #[error("keyframe {keyframe}: the transform of joint {joint} is singular")]
    SingularTransform {
        /// The 0-based keyframe index.
        keyframe: usize,
        /// The joint index.
        joint: usize,
    },
}

/// Where time `t` falls: blend `keys[lo]` and `keys[hi]` with weight `a` on `hi`
/// (`lo == hi` means "copy that keyframe").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bracket {
    /// Index of the keyframe at or before `t`.
    pub lo: usize,
    /// Index of the keyframe after `t` (equal to `lo` when copying one keyframe).
    pub hi: usize,
    /// Blend weight of `keys[hi]`, in `[0, 1)`.
    pub a: f64,
}

/// The bracket of `t` in ascending `times` (non-empty). NaN maps to the first keyframe.
pub fn bracket(times: &[f64], t: f64) -> Bracket {
    let hi = times.partition_point(|&x| x < t);
    if hi == 0 {
        Bracket {
            lo: 0,
            hi: 0,
            a: 0.0,
        }
    } else if hi >= times.len() {
        let last = times.len() - 1;
        Bracket {
            lo: last,
            hi: last,
            a: 0.0,
        }
    } else if times[hi] == t {
        Bracket { lo: hi, hi, a: 0.0 }
    } else {
        let (t_lo, t_hi) = (times[hi - 1], times[hi]);
        Bracket {
            lo: hi - 1,
            hi,
            a: (t - t_lo) / (t_hi - t_lo),
        }
    }
}

fn validate_times(times: &[f64], keyframes: usize) -> Result<(), AnimationError> {
    if times.len() != keyframes {
        return Err(AnimationError::LengthMismatch {
            times: times.len(),
            keyframes,
        });
    }
    if times.is_empty() {
        return Err(AnimationError::Empty);
    }
    for (k, &time) in times.iter().enumerate() {
        if !time.is_finite() {
            return Err(AnimationError::NonFiniteTime { keyframe: k, time });
        }
        if k > 0 && time <= times[k - 1] {
            return Err(AnimationError::TimeNotIncreasing {
                keyframe: k,
                time,
                previous: times[k - 1],
            });
        }
    }
    Ok(())
}

/// One key decomposed for blending.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Decomposed {
    scale: DVec3,
    rotation: DQuat,
    translation: DVec3,
}

/// Skeleton animation: per keyframe, the local transform `parent_from_joint` of every joint.
#[derive(Debug, Clone, PartialEq)]
pub struct SkeletonTrack {
    times: Vec<f64>,
    keys: Vec<Vec<DAffine3>>,
    decomposed: Vec<Vec<Decomposed>>,
}

impl SkeletonTrack {
    /// Validates (strictly ascending finite times, same joint count in every keyframe, finite
    /// non-singular transforms) and pre-decomposes every key into scale, rotation, translation.
    pub fn new(times: Vec<f64>, keys: Vec<Vec<DAffine3>>) -> Result<Self, AnimationError> {
        validate_times(&times, keys.len())?;
        let num_joints = keys[0].len();
        let mut decomposed = Vec::with_capacity(keys.len());
        for (k, key) in keys.iter().enumerate() {
            if key.len() != num_joints {
                return Err(AnimationError::KeyframeSize {
                    keyframe: k,
                    what: "joints",
                    expected: num_joints,
                    actual: key.len(),
                });
            }
            let mut row = Vec::with_capacity(num_joints);
            for (j, transform) in key.iter().enumerate() {
                if !transform.is_finite() {
                    return Err(AnimationError::NonFinite {
                        keyframe: k,
                        what: "joint transform",
                        index: j,
                    });
                }
                let det = transform.matrix3.determinant();
                if det.abs() <= SINGULAR_DETERMINANT || !det.is_finite() {
                    return Err(AnimationError::SingularTransform {
                        keyframe: k,
                        joint: j,
                    });
                }
                let (scale, rotation, translation) = transform.to_scale_rotation_translation();
                row.push(Decomposed {
                    scale,
                    rotation: rotation.normalize(),
                    translation,
                });
            }
            decomposed.push(row);
        }
        Ok(Self {
            times,
            keys,
            decomposed,
        })
    }

    /// Keyframe times in seconds (strictly ascending).
    pub fn times(&self) -> &[f64] {
        &self.times
    }

    /// Keyframes: `keys()[k][j]` = `parent_from_joint` of joint j at keyframe k.
    pub fn keys(&self) -> &[Vec<DAffine3>] {
        &self.keys
    }

    /// Number of keyframes (at least 1).
    pub fn num_keyframes(&self) -> usize {
        self.times.len()
    }

    /// Number of joints `#J` in every keyframe.
    pub fn num_joints(&self) -> usize {
        self.keys[0].len()
    }

    /// Local transforms at time `t` (seconds) into `out` (`#J`). No allocation. At a keyframe
    /// time (or outside the track) the keyframe is copied exactly.
    pub fn sample(&self, t: f64, out: &mut [DAffine3]) {
        let b = bracket(&self.times, t);
        if b.lo == b.hi {
            out.copy_from_slice(&self.keys[b.lo]);
            return;
        }
        let (lo, hi) = (&self.decomposed[b.lo], &self.decomposed[b.hi]);
        for ((o, p), q) in out.iter_mut().zip(lo).zip(hi) {
            // glam's slerp negates `end` when the dot product is negative: shorter arc.
            let rotation = p.rotation.slerp(q.rotation, b.a);
            *o = DAffine3::from_scale_rotation_translation(
                p.scale.lerp(q.scale, b.a),
                rotation,
                p.translation.lerp(q.translation, b.a),
            );
        }
    }
}

/// Cage animation: per keyframe, the offset of every rest-cage vertex from the original rest
/// cage (C = C_original + offset).
#[derive(Debug, Clone, PartialEq)]
pub struct CageTrack {
    times: Vec<f64>,
    offsets: Vec<Vec<DVec3>>,
}

impl CageTrack {
    /// Validates strictly ascending finite times, equal vertex counts and finite offsets.
    pub fn new(times: Vec<f64>, offsets: Vec<Vec<DVec3>>) -> Result<Self, AnimationError> {
        validate_times(&times, offsets.len())?;
        let n = offsets[0].len();
        for (k, key) in offsets.iter().enumerate() {
            if key.len() != n {
                return Err(AnimationError::KeyframeSize {
                    keyframe: k,
                    what: "cage vertices",
                    expected: n,
                    actual: key.len(),
                });
            }
            if let Some(index) = key.iter().position(|d| !d.is_finite()) {
                return Err(AnimationError::NonFinite {
                    keyframe: k,
                    what: "cage vertex offset",
                    index,
                });
            }
        }
        Ok(Self { times, offsets })
    }

    /// Keyframe times in seconds (strictly ascending).
    pub fn times(&self) -> &[f64] {
        &self.times
    }

    /// `offsets()[k][c]` = offset of cage vertex c at keyframe k.
    pub fn offsets(&self) -> &[Vec<DVec3>] {
        &self.offsets
    }

    /// Number of keyframes (at least 1).
    pub fn num_keyframes(&self) -> usize {
        self.times.len()
    }

    /// Number of cage vertices `#C` in every keyframe.
    pub fn num_cage_vertices(&self) -> usize {
        self.offsets[0].len()
    }

    /// Offsets at time `t` (seconds) into `out` (`#C`), linear blend, clamped. No allocation.
    pub fn sample(&self, t: f64, out: &mut [DVec3]) {
        let b = bracket(&self.times, t);
        if b.lo == b.hi {
            out.copy_from_slice(&self.offsets[b.lo]);
            return;
        }
        for ((o, p), q) in out
            .iter_mut()
            .zip(&self.offsets[b.lo])
            .zip(&self.offsets[b.hi])
        {
            *o = p.lerp(*q, b.a);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn bracket_clamps_and_blends() {
        let times = [0.0, 1.0, 3.0];
        assert_eq!(
            bracket(&times, -1.0),
            Bracket {
                lo: 0,
                hi: 0,
                a: 0.0
            }
        );
        assert_eq!(
            bracket(&times, 0.0),
            Bracket {
                lo: 0,
                hi: 0,
                a: 0.0
            }
        );
        assert_eq!(
            bracket(&times, 2.0),
            Bracket {
                lo: 1,
                hi: 2,
                a: 0.5
            }
        );
        assert_eq!(
            bracket(&times, 3.0),
            Bracket {
                lo: 2,
                hi: 2,
                a: 0.0
            }
        );
        assert_eq!(
            bracket(&times, 9.0),
            Bracket {
                lo: 2,
                hi: 2,
                a: 0.0
            }
        );
        assert_eq!(bracket(&times, f64::NAN).lo, 0);
    }

    #[test]
    fn skeleton_track_lerps_translation_and_slerps_rotation() {
        let k0 = vec![DAffine3::from_translation(DVec3::ZERO)];
        let k1 = vec![DAffine3::from_rotation_translation(
            DQuat::from_rotation_z(PI / 2.0),
            DVec3::new(2.0, 0.0, 0.0),
        )];
        let track = SkeletonTrack::new(vec![1.0, 2.0], vec![k0.clone(), k1.clone()]).unwrap();
        let mut out = [DAffine3::ZERO];
        track.sample(1.5, &mut out);
        let expect = DAffine3::from_rotation_translation(
            DQuat::from_rotation_z(PI / 4.0),
            DVec3::new(1.0, 0.0, 0.0),
        );
        assert!(out[0].abs_diff_eq(expect, 1e-14), "{:?}", out[0]);
        track.sample(0.0, &mut out);
        assert_eq!(out[0], k0[0]);
        track.sample(5.0, &mut out);
        assert_eq!(out[0], k1[0]);
        track.sample(2.0, &mut out);
        assert_eq!(out[0], k1[0]);
    }

    #[test]
    fn slerp_takes_the_shorter_arc_across_the_antipodal_hemisphere() {
        // 170° and −170° about z: the short way goes through 180°, not through 0°.
        let k0 = vec![DAffine3::from_rotation_z(170f64.to_radians())];
        let k1 = vec![DAffine3::from_rotation_z(-170f64.to_radians())];
        let mut track = SkeletonTrack::new(vec![0.0, 1.0], vec![k0, k1]).unwrap();
        // Store the second key with the sign that puts it in the opposite hemisphere (q and −q
        // are the same rotation; files and decompositions may give either).
        let q0 = track.decomposed[0][0].rotation;
        let q1 = &mut track.decomposed[1][0].rotation;
        if q0.dot(*q1) > 0.0 {
            *q1 = -*q1;
        }
        assert!(q0.dot(*q1) < 0.0, "test must exercise opposite hemispheres");
        let mut out = [DAffine3::ZERO];
        track.sample(0.5, &mut out);
        let half = DAffine3::from_rotation_z(PI);
        assert!(out[0].abs_diff_eq(half, 1e-12), "{:?}", out[0]);
        track.sample(0.25, &mut out);
        assert!(out[0].abs_diff_eq(DAffine3::from_rotation_z(175f64.to_radians()), 1e-12));
    }

    #[test]
    fn scale_is_blended_too() {
        let k0 = vec![DAffine3::from_scale(DVec3::splat(1.0))];
        let k1 = vec![DAffine3::from_scale(DVec3::splat(3.0))];
        let track = SkeletonTrack::new(vec![0.0, 1.0], vec![k0, k1]).unwrap();
        let mut out = [DAffine3::ZERO];
        track.sample(0.5, &mut out);
        assert!(out[0].abs_diff_eq(DAffine3::from_scale(DVec3::splat(2.0)), 1e-14));
    }

    #[test]
    fn cage_track_lerps_and_clamps() {
        let track = CageTrack::new(
            vec![0.0, 1.5, 3.0],
            vec![
                vec![DVec3::ZERO, DVec3::X],
                vec![DVec3::new(3.0, 0.0, 0.0), DVec3::X],
                vec![DVec3::ZERO, DVec3::Y],
            ],
        )
        .unwrap();
        let mut out = [DVec3::ZERO; 2];
        track.sample(0.5, &mut out);
        assert!(out[0].abs_diff_eq(DVec3::new(1.0, 0.0, 0.0), 1e-15));
        assert_eq!(out[1], DVec3::X);
        track.sample(2.25, &mut out);
        assert!(out[0].abs_diff_eq(DVec3::new(1.5, 0.0, 0.0), 1e-15));
        assert!(out[1].abs_diff_eq(DVec3::new(0.5, 0.5, 0.0), 1e-15));
        track.sample(-3.0, &mut out);
        assert_eq!(out, [DVec3::ZERO, DVec3::X]);
        track.sample(30.0, &mut out);
        assert_eq!(out, [DVec3::ZERO, DVec3::Y]);
    }

    #[test]
    fn construction_rejects_inconsistent_tracks() {
        let one = || vec![DVec3::ZERO];
        assert_eq!(CageTrack::new(vec![], vec![]), Err(AnimationError::Empty));
        assert!(matches!(
            CageTrack::new(vec![0.0, 0.0], vec![one(), one()]),
            Err(AnimationError::TimeNotIncreasing { keyframe: 1, .. })
        ));
        assert!(matches!(
            CageTrack::new(vec![0.0], vec![one(), one()]),
            Err(AnimationError::LengthMismatch { .. })
        ));
        assert!(matches!(
            CageTrack::new(vec![0.0, 1.0], vec![one(), vec![]]),
            Err(AnimationError::KeyframeSize { keyframe: 1, .. })
        ));
        assert!(matches!(
            CageTrack::new(vec![0.0], vec![vec![DVec3::NAN]]),
            Err(AnimationError::NonFinite { .. })
        ));
        assert!(matches!(
            CageTrack::new(vec![f64::NAN], vec![one()]),
            Err(AnimationError::NonFiniteTime { .. })
        ));
        assert!(matches!(
            SkeletonTrack::new(vec![0.0], vec![vec![DAffine3::ZERO]]),
            Err(AnimationError::SingularTransform {
                keyframe: 0,
                joint: 0
            })
        ));
    }
}
