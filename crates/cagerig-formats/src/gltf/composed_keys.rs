//! Extra keys where a joint's local transform composes several animated nodes.
//!
//! A joint's `parent_from_joint` is the product of the node locals from its parent joint
//! (excluded) down to its own node, and for a root every ancestor above it: nodes that are not
//! joints of the chosen skin (the joints of another skeleton it hangs from, an animated armature
//! node). The skeleton track lerps translation and scale and slerps rotation between its keys,
//! which is exact for the file's LINEAR channels on one node, but not for a product in which a
//! node turns above another animated node or above a translation: the composed origin moves on
//! an arc, and the product of two slerps is not a slerp. For such joints
//! ([`composes_several_motions`]) each interval between keys is checked at a quarter, a half and
//! three quarters against the track's interpolation and split at its midpoint while the
//! difference exceeds the tolerance ([`refine_composed_keys`]).

use glam::{DAffine3, DQuat, DVec3};

/// Deepest split of one interval between the file's keys (2^12 pieces).
pub const MAX_DEPTH: usize = 12;
/// Joint-keys (keys × joints) the refinement may add in all, bounding the track's memory.
pub const MAX_ADDED_JOINT_KEYS: usize = 500_000;

/// How a chain's nodes are animated, top first.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NodeMotion {
    /// A rotation or scale channel targets the node.
    pub turns: bool,
    /// Any channel targets the node.
    pub animated: bool,
    /// The node's rest translation is not zero.
    pub offset: bool,
}

/// Whether a joint's composed local (nodes `chain`, top first, described by `motion`) may leave
/// the track's interpolation between keys: a node that turns (rotation or scale) with an
/// animated node or a translation below it in the chain.
pub fn composes_several_motions(chain: &[NodeMotion]) -> bool {
    let Some(first) = chain.iter().position(|m| m.turns) else {
        return false;
    };
    chain[first + 1..].iter().any(|m| m.animated || m.offset)
}

/// The outcome of [`refine_composed_keys`].
#[derive(Debug, Clone, PartialEq)]
pub struct RefinedKeys {
    /// Key times, sorted, every input time kept.
    pub times: Vec<f64>,
    /// The composed locals at each time (`#times × #J`).
    pub keys: Vec<Vec<DAffine3>>,
    /// Keys added to the input times.
    pub added: usize,
    /// The largest difference measured at a check point of an interval that was not split
    /// (translation, plus rotation and scale times the length scale).
    pub largest_checked: f64,
    /// True when [`MAX_DEPTH`] or [`MAX_ADDED_JOINT_KEYS`] stopped a split above the tolerance.
    pub capped: bool,
}

/// Adds keys between `times` (sorted) until the track's interpolation of the composed locals of
/// the joints `suspects` is within `tolerance` of `evaluate(t)` (the exact composed locals,
/// `#J`) at every check point. Rotation and scale differences count times `length_scale` (the
/// size of the skeleton), so the tolerance is a distance. Intervals no longer than
/// `shortest` seconds are not checked: the ramps before STEP keys, which are inexact by design.
pub fn refine_composed_keys(
    times: &[f64],
    suspects: &[usize],
    length_scale: f64,
    tolerance: f64,
    shortest: f64,
    mut evaluate: impl FnMut(f64) -> Vec<DAffine3>,
) -> RefinedKeys {
    let first: Vec<Vec<DAffine3>> = times.iter().map(|&t| evaluate(t)).collect();
    let num_joints = first.first().map_or(1, Vec::len).max(1);
    let mut out = RefinedKeys {
        times: Vec::with_capacity(times.len()),
        keys: Vec::with_capacity(times.len()),
        added: 0,
        largest_checked: 0.0,
        capped: false,
    };
    let mut budget = (MAX_ADDED_JOINT_KEYS / num_joints).max(1);
    let mut check = Check {
        suspects,
        length_scale,
        tolerance,
        shortest,
        evaluate: &mut evaluate,
    };
    for (k, key) in first.iter().enumerate() {
        if k > 0 {
            check.split(
                (times[k - 1], &first[k - 1]),
                (times[k], key),
                0,
                &mut budget,
                &mut out,
            );
        }
        out.times.push(times[k]);
        out.keys.push(key.clone());
    }
    out
}

/// What one interval is checked with.
struct Check<'a, F> {
    suspects: &'a [usize],
    length_scale: f64,
    tolerance: f64,
    shortest: f64,
    evaluate: &'a mut F,
}

impl<F: FnMut(f64) -> Vec<DAffine3>> Check<'_, F> {
    /// Checks `(t0, t1)`; pushes the keys added strictly inside it, in order.
    fn split(
        &mut self,
        (t0, k0): (f64, &[DAffine3]),
        (t1, k1): (f64, &[DAffine3]),
        depth: usize,
        budget: &mut usize,
        out: &mut RefinedKeys,
    ) {
        if t1 - t0 <= self.shortest {
            return;
        }
        let mut worst: f64 = 0.0;
        let mut middle = None;
        for a in [0.5, 0.25, 0.75] {
            let exact = (self.evaluate)(t0 + a * (t1 - t0));
            for &j in self.suspects {
                worst = worst.max(self.difference(exact[j], interpolate(k0[j], k1[j], a)));
            }
            if a == 0.5 {
                middle = Some(exact);
            }
            if worst > self.tolerance {
                break;
            }
        }
        let Some(middle) = middle else {
            return;
        };
        if worst <= self.tolerance {
            out.largest_checked = out.largest_checked.max(worst);
            return;
        }
        if depth >= MAX_DEPTH || *budget == 0 {
            out.capped = true;
            out.largest_checked = out.largest_checked.max(worst);
            return;
        }
        *budget -= 1;
        let tm = 0.5 * (t0 + t1);
        self.split((t0, k0), (tm, &middle), depth + 1, budget, out);
        out.times.push(tm);
        out.keys.push(middle.clone());
        out.added += 1;
        self.split((tm, &middle), (t1, k1), depth + 1, budget, out);
    }

    /// Translation difference plus rotation angle and scale difference times the length scale.
    fn difference(&self, a: DAffine3, b: DAffine3) -> f64 {
        let (sa, ra, ta) = decompose(a);
        let (sb, rb, tb) = decompose(b);
        let relative = ra.inverse() * rb;
        let angle = 2.0 * relative.xyz().length().atan2(relative.w.abs());
        ta.distance(tb) + self.length_scale * (angle + (sa - sb).abs().max_element())
    }
}

/// Scale, unit rotation and translation, as the skeleton track decomposes a key.
fn decompose(m: DAffine3) -> (DVec3, DQuat, DVec3) {
    let (scale, rotation, translation) = m.to_scale_rotation_translation();
    (scale, rotation.normalize(), translation)
}

/// The skeleton track's interpolation between two keys at fraction `a`: lerp translation and
/// scale, slerp rotation along the shorter arc.
fn interpolate(p: DAffine3, q: DAffine3, a: f64) -> DAffine3 {
    let (sp, rp, tp) = decompose(p);
    let (sq, rq, tq) = decompose(q);
    DAffine3::from_scale_rotation_translation(sp.lerp(sq, a), rp.slerp(rq, a), tp.lerp(tq, a))
}

#[cfg(test)]
mod tests {
    use super::*;

    const STILL: NodeMotion = NodeMotion {
        turns: false,
        animated: false,
        offset: false,
    };
    const TURNING: NodeMotion = NodeMotion {
        turns: true,
        animated: true,
        offset: false,
    };
    const OFFSET: NodeMotion = NodeMotion {
        turns: false,
        animated: false,
        offset: true,
    };

    #[test]
    fn one_turning_node_or_a_turn_at_the_bottom_interpolates_exactly() {
        assert!(!composes_several_motions(&[STILL, STILL]));
        assert!(!composes_several_motions(&[OFFSET, TURNING]));
        assert!(!composes_several_motions(&[TURNING, STILL]));
        assert!(composes_several_motions(&[TURNING, OFFSET]));
        assert!(composes_several_motions(&[TURNING, TURNING]));
    }

    /// A node turning about z by ω t with a child 10 units along x: the composed origin moves
    /// on a circle of radius 10. Keys every second at ω = 1 rad/s leave a chord 10(1 − cos ¼)
    /// ≈ 0.31 from the arc at the middle; refined to 1e-6 the midpoints of the final intervals
    /// are within it, and the refinement adds about √(0.31 / 1e-6) / 2 keys per second.
    #[test]
    fn an_arc_is_split_until_the_chord_is_within_the_tolerance() {
        let evaluate = |t: f64| {
            vec![
                DAffine3::from_rotation_z(t)
                    * DAffine3::from_translation(DVec3::new(10.0, 0.0, 0.0)),
            ]
        };
        let refined = refine_composed_keys(&[0.0, 1.0, 2.0], &[0], 10.0, 1e-6, 0.0, evaluate);
        assert!(!refined.capped);
        assert_eq!(refined.times.first(), Some(&0.0));
        assert_eq!(refined.times.last(), Some(&2.0));
        assert!(refined.times.windows(2).all(|w| w[0] < w[1]));
        assert!(refined.times.contains(&1.0));
        assert!(refined.largest_checked <= 1e-6);
        // Sagitta of a chord of angle h: 10 (1 − cos(h/2)) ≤ 1e-6 needs h ≤ 8.9e-4: at most
        // 2^11 pieces a second, at least 2^10.
        assert!(
            (2 * 1024..=2 * 2048).contains(&(refined.added + 1)),
            "{}",
            refined.added
        );
        for (t, key) in refined.times.iter().zip(&refined.keys) {
            assert_eq!(*key, evaluate(*t));
        }
        // Between the new keys the interpolation follows the arc.
        for w in refined.times.windows(2) {
            let t = 0.5 * (w[0] + w[1]);
            let chord = interpolate(evaluate(w[0])[0], evaluate(w[1])[0], 0.5).translation;
            assert!(chord.distance(evaluate(t)[0].translation) <= 1e-6);
        }
    }

    #[test]
    fn a_track_the_interpolation_follows_gets_no_key() {
        let evaluate = |t: f64| {
            vec![DAffine3::from_translation(DVec3::new(t, 0.0, 0.0)) * DAffine3::from_rotation_z(t)]
        };
        let refined = refine_composed_keys(&[0.0, 1.0], &[0], 1.0, 1e-9, 0.0, evaluate);
        assert_eq!(refined.added, 0);
        assert_eq!(refined.times, vec![0.0, 1.0]);
        assert!(refined.largest_checked <= 1e-9);
    }

    #[test]
    fn the_depth_cap_is_reported() {
        let evaluate = |t: f64| vec![DAffine3::from_translation(DVec3::new(t.sin(), 0.0, 0.0))];
        let refined = refine_composed_keys(&[0.0, 1000.0], &[0], 1.0, 1e-12, 0.0, evaluate);
        assert!(refined.capped);
        assert!(refined.added < 1 << (MAX_DEPTH + 1));
    }

    /// A STEP channel's ramp (the key 1e-6 s before the step, where the track blends what the
    /// file holds until the step) is left as it is: no key inside it, nothing capped.
    #[test]
    fn the_ramp_before_a_step_is_not_split() {
        let evaluate = |t: f64| {
            let x = if t < 1.0 { 0.0 } else { 1.0 };
            vec![DAffine3::from_translation(DVec3::new(x, 0.0, 0.0))]
        };
        let times = [0.0, 1.0 - 1e-6, 1.0, 2.0];
        let refined = refine_composed_keys(&times, &[0], 1.0, 1e-9, 2e-6, evaluate);
        assert_eq!(refined.added, 0);
        assert!(!refined.capped);
        assert_eq!(refined.times, times.to_vec());
        // Without the floor the ramp is split to the depth cap.
        let split = refine_composed_keys(&times, &[0], 1.0, 1e-9, 0.0, evaluate);
        assert!(split.capped && split.added == MAX_DEPTH, "{}", split.added);
    }
}
