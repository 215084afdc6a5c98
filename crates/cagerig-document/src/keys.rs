//! Keyframes of the two tracks the editor animates independently: the skeleton track (the
//! current pose S') and the cage track (the rest cage C). Playback turns them into the
//! library's [`SkeletonTrack`] / [`CageTrack`] and plays them with its [`AnimationPlayer`], so
//! the editor samples exactly like `cagerig animate`.

use std::path::Path;

use cagerig::animation::{CageTrack, SkeletonTrack};
use cagerig::io::{FloatFormat, SkeletonAnimationVersion};
use cagerig::playback::{AnimationPlayer, PoseChannels};
use cagerig::pose::{local_transform, rotation_of};
use cagerig::session::RigSession;
use glam::{DAffine3, DQuat, DVec3};
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Two keys closer than this (seconds) are the same key.
pub const SAME_TIME: f64 = 1e-6;

/// Which track a key is on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Track {
    Skeleton,
    Cage,
}

/// A pose of the current skeleton (all `#J`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SkeletonKey {
    pub time: f64,
    pub rotations: Vec<DQuat>,
    pub scales: Vec<DVec3>,
    pub translation_offsets: Vec<DVec3>,
}

/// A rest cage C (`#C`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CageKey {
    pub time: f64,
    pub rest_cage: Vec<DVec3>,
}

/// Both tracks, each sorted by strictly increasing time.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Keys {
    pub skeleton: Vec<SkeletonKey>,
    pub cage: Vec<CageKey>,
    /// Playback holds SkelUp: the skeleton keys already carry the rest joints' motion (a
    /// cagerig glTF export with a cage track, loaded with its morph weights as cage keys; see
    /// [`AnimationPlayer::holding_rest_skeleton`]).
    #[serde(default)]
    pub hold_rest_skeleton: bool,
}

#[derive(Debug, Error)]
pub enum KeyError {
    #[error("{track:?} key {index}: time {time} is not a finite number ≥ 0")]
    BadTime {
        track: Track,
        index: usize,
        time: f64,
    },
    #[error("{track:?} key {index}: time {time} is not after the previous key's {previous}")]
    NotIncreasing {
        track: Track,
        index: usize,
        time: f64,
        previous: f64,
    },
    #[error("{track:?} key {index}: has {actual} {what}, the rig has {expected}")]
    Size {
        track: Track,
        index: usize,
        what: &'static str,
        expected: usize,
        actual: usize,
    },
    #[error("{track:?} key {index}: {what} {element} is not finite")]
    NonFinite {
        track: Track,
        index: usize,
        what: &'static str,
        element: usize,
    },
    #[error("a key already exists at {time} s on the {track:?} track")]
    Occupied { track: Track, time: f64 },
    #[error("{0}")]
    Rig(#[from] cagerig::RigError),
    #[error("{0}")]
    Animation(#[from] cagerig::animation::AnimationError),
    #[error("{0}")]
    File(#[from] cagerig::io::ParseError),
}

fn insert_sorted<K>(keys: &mut Vec<K>, key: K, time_of: impl Fn(&K) -> f64) -> usize {
    let t = time_of(&key);
    if let Some(i) = keys.iter().position(|k| (time_of(k) - t).abs() < SAME_TIME) {
        keys[i] = key;
        return i;
    }
    let i = keys.partition_point(|k| time_of(k) < t);
    keys.insert(i, key);
    i
}

/// Original local translations of the loaded skeleton (`#J`; roots: world translation).
fn original_local_translations(session: &RigSession) -> Vec<DVec3> {
    let skeleton = session.skeleton();
    let mut locals = vec![DAffine3::IDENTITY; skeleton.len()];
    skeleton.locals_from_worlds(&skeleton.rest_world_from_joint(), &mut locals);
    locals.iter().map(|l| l.translation).collect()
}

impl Keys {
    /// Keys the current pose at `time` (replacing a key at the same time). Returns its index.
    pub fn set_skeleton_key(&mut self, time: f64, session: &RigSession) -> usize {
        insert_sorted(
            &mut self.skeleton,
            SkeletonKey {
                time,
                rotations: session.posed_local_rotations().to_vec(),
                scales: session.posed_local_scales().to_vec(),
                translation_offsets: session.translation_offsets().to_vec(),
            },
            |k| k.time,
        )
    }

    /// Keys the current rest cage at `time` (replacing a key at the same time).
    pub fn set_cage_key(&mut self, time: f64, session: &RigSession) -> usize {
        insert_sorted(
            &mut self.cage,
            CageKey {
                time,
                rest_cage: session.rest_cage().to_vec(),
            },
            |k| k.time,
        )
    }

    pub fn len(&self, track: Track) -> usize {
        match track {
            Track::Skeleton => self.skeleton.len(),
            Track::Cage => self.cage.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.skeleton.is_empty() && self.cage.is_empty()
    }

    pub fn time(&self, track: Track, index: usize) -> Option<f64> {
        match track {
            Track::Skeleton => self.skeleton.get(index).map(|k| k.time),
            Track::Cage => self.cage.get(index).map(|k| k.time),
        }
    }

    /// Index of the key of `track` at `time` (within [`SAME_TIME`]), if any.
    pub fn index_at(&self, track: Track, time: f64) -> Option<usize> {
        (0..self.len(track)).find(|&i| {
            self.time(track, i)
                .is_some_and(|t| (t - time).abs() < SAME_TIME)
        })
    }

    /// Removes a key; false if there is none at `index`.
    pub fn delete(&mut self, track: Track, index: usize) -> bool {
        let len = self.len(track);
        if index >= len {
            return false;
        }
        match track {
            Track::Skeleton => drop(self.skeleton.remove(index)),
            Track::Cage => drop(self.cage.remove(index)),
        }
        true
    }

    /// Moves a key to `time` (≥ 0), refusing to land on another key. Returns its new index.
    pub fn move_key(&mut self, track: Track, index: usize, time: f64) -> Result<usize, KeyError> {
        if !(time.is_finite() && time >= 0.0) {
            return Err(KeyError::BadTime { track, index, time });
        }
        let occupied = |times: &mut dyn Iterator<Item = f64>| {
            times
                .enumerate()
                .any(|(i, t)| i != index && (t - time).abs() < SAME_TIME)
        };
        match track {
            Track::Skeleton => {
                if occupied(&mut self.skeleton.iter().map(|k| k.time)) {
                    return Err(KeyError::Occupied { track, time });
                }
                let mut key = self.skeleton.remove(index);
                key.time = time;
                Ok(insert_sorted(&mut self.skeleton, key, |k| k.time))
            }
            Track::Cage => {
                if occupied(&mut self.cage.iter().map(|k| k.time)) {
                    return Err(KeyError::Occupied { track, time });
                }
                let mut key = self.cage.remove(index);
                key.time = time;
                Ok(insert_sorted(&mut self.cage, key, |k| k.time))
            }
        }
    }

    /// Last key time over both tracks (0 without keys).
    pub fn duration(&self) -> f64 {
        let s = self.skeleton.last().map_or(0.0, |k| k.time);
        let c = self.cage.last().map_or(0.0, |k| k.time);
        s.max(c)
    }

    /// Checks keys read from a file against the rig: times, sizes, finite values.
    pub fn validate(&self, session: &RigSession) -> Result<(), KeyError> {
        let nj = session.skeleton().len();
        let nc = session.rest_cage().len();
        let check_times = |track: Track, times: &mut dyn Iterator<Item = f64>| {
            let mut previous: Option<f64> = None;
            for (index, time) in times.enumerate() {
                if !(time.is_finite() && time >= 0.0) {
                    return Err(KeyError::BadTime { track, index, time });
                }
                if let Some(p) = previous
                    && time <= p
                {
                    return Err(KeyError::NotIncreasing {
                        track,
                        index,
                        time,
                        previous: p,
                    });
                }
                previous = Some(time);
            }
            Ok(())
        };
        check_times(Track::Skeleton, &mut self.skeleton.iter().map(|k| k.time))?;
        check_times(Track::Cage, &mut self.cage.iter().map(|k| k.time))?;
        let track = Track::Skeleton;
        for (index, k) in self.skeleton.iter().enumerate() {
            for (what, actual) in [
                ("rotations", k.rotations.len()),
                ("scales", k.scales.len()),
                ("translation offsets", k.translation_offsets.len()),
            ] {
                if actual != nj {
                    return Err(KeyError::Size {
                        track,
                        index,
                        what,
                        expected: nj,
                        actual,
                    });
                }
            }
            let bad = (0..nj).find(|&j| {
                !k.rotations[j].is_finite()
                    || k.rotations[j].length_squared() == 0.0
                    || !k.scales[j].is_finite()
                    || !k.translation_offsets[j].is_finite()
            });
            if let Some(element) = bad {
                return Err(KeyError::NonFinite {
                    track,
                    index,
                    what: "joint",
                    element,
                });
            }
        }
        let track = Track::Cage;
        for (index, k) in self.cage.iter().enumerate() {
            if k.rest_cage.len() != nc {
                return Err(KeyError::Size {
                    track,
                    index,
                    what: "cage vertices",
                    expected: nc,
                    actual: k.rest_cage.len(),
                });
            }
            if let Some(element) = k.rest_cage.iter().position(|p| !p.is_finite()) {
                return Err(KeyError::NonFinite {
                    track,
                    index,
                    what: "cage vertex",
                    element,
                });
            }
        }
        Ok(())
    }

    /// The skeleton keys as the library's track of local transforms (`None` without keys).
    pub fn skeleton_track(&self, session: &RigSession) -> Result<Option<SkeletonTrack>, KeyError> {
        if self.skeleton.is_empty() {
            return Ok(None);
        }
        let original = original_local_translations(session);
        let keys = self
            .skeleton
            .iter()
            .map(|k| {
                (0..original.len())
                    .map(|j| {
                        local_transform(
                            original[j] + k.translation_offsets[j],
                            k.rotations[j],
                            k.scales[j],
                        )
                    })
                    .collect()
            })
            .collect();
        let times = self.skeleton.iter().map(|k| k.time).collect();
        Ok(Some(SkeletonTrack::new(times, keys)?))
    }

    /// The cage keys as offsets from the loaded rest cage C₀ (`None` without keys).
    pub fn cage_track(&self, session: &RigSession) -> Result<Option<CageTrack>, KeyError> {
        if self.cage.is_empty() {
            return Ok(None);
        }
        let c0 = session.original_rest_cage();
        let offsets = self
            .cage
            .iter()
            .map(|k| k.rest_cage.iter().zip(c0).map(|(c, o)| *c - *o).collect())
            .collect();
        let times = self.cage.iter().map(|k| k.time).collect();
        Ok(Some(CageTrack::new(times, offsets)?))
    }

    /// A player of both tracks on `session` (`None` without keys).
    pub fn player(&self, session: &RigSession) -> Result<Option<AnimationPlayer>, KeyError> {
        if self.is_empty() {
            return Ok(None);
        }
        let player = AnimationPlayer::with_channels(
            session,
            self.skeleton_track(session)?,
            self.cage_track(session)?,
            PoseChannels::Full,
        )?
        .holding_rest_skeleton(self.hold_rest_skeleton);
        Ok(Some(player))
    }

    /// Replaces the skeleton keys with a skeleton animation file of the paper's tool (local
    /// rotations and root motion; scales stay at rest).
    pub fn import_skeleton_animation(
        &mut self,
        path: &Path,
        session: &RigSession,
    ) -> Result<usize, KeyError> {
        let (track, _version) = cagerig::io::read_skeleton_animation(path, session.skeleton())?;
        self.hold_rest_skeleton = false;
        let original = original_local_translations(session);
        let skeleton = session.skeleton();
        self.skeleton = track
            .times()
            .iter()
            .zip(track.keys())
            .map(|(&time, locals)| SkeletonKey {
                time,
                rotations: locals.iter().map(|l| rotation_of(&l.matrix3)).collect(),
                scales: session.rest_local_scales().to_vec(),
                translation_offsets: (0..locals.len())
                    .map(|j| match skeleton.parent(j) {
                        None => locals[j].translation - original[j],
                        Some(_) => DVec3::ZERO,
                    })
                    .collect(),
            })
            .collect();
        Ok(self.skeleton.len())
    }

    /// Replaces the cage keys with a cage track (offsets from C₀), e.g. an imported animation's
    /// morph weights ([`cagerig_formats::morph_cage_track`]).
    pub fn set_cage_track(&mut self, track: &CageTrack, session: &RigSession) -> usize {
        let c0 = session.original_rest_cage();
        self.cage = track
            .times()
            .iter()
            .zip(track.offsets())
            .map(|(&time, offsets)| CageKey {
                time,
                rest_cage: c0.iter().zip(offsets).map(|(c, o)| *c + *o).collect(),
            })
            .collect();
        self.cage.len()
    }

    /// Replaces the skeleton keys with an imported (glTF / FBX) animation's track of local
    /// transforms, every channel kept (rotation, scale, translation of every joint); playback
    /// no longer holds SkelUp.
    pub fn set_skeleton_track(&mut self, track: &SkeletonTrack, session: &RigSession) -> usize {
        self.hold_rest_skeleton = false;
        let original = original_local_translations(session);
        self.skeleton = track
            .times()
            .iter()
            .zip(track.keys())
            .map(|(&time, locals)| {
                let mut key = SkeletonKey {
                    time,
                    rotations: Vec::with_capacity(locals.len()),
                    scales: Vec::with_capacity(locals.len()),
                    translation_offsets: Vec::with_capacity(locals.len()),
                };
                for (local, o) in locals.iter().zip(&original) {
                    let (scale, rotation, translation) = local.to_scale_rotation_translation();
                    key.rotations.push(rotation);
                    key.scales.push(scale);
                    key.translation_offsets.push(translation - *o);
                }
                key
            })
            .collect();
        self.skeleton.len()
    }

    /// Replaces the cage keys with a cage animation file (offsets from C₀).
    pub fn import_cage_animation(
        &mut self,
        path: &Path,
        session: &RigSession,
    ) -> Result<usize, KeyError> {
        let track = cagerig::io::read_cage_animation(path, session.rest_cage().len())?;
        Ok(self.set_cage_track(&track, session))
    }

    /// Writes the skeleton keys as a skeleton animation file (V3: global frames).
    pub fn export_skeleton_animation(
        &self,
        path: &Path,
        session: &RigSession,
    ) -> Result<bool, KeyError> {
        let Some(track) = self.skeleton_track(session)? else {
            return Ok(false);
        };
        cagerig::io::write_skeleton_animation(
            path,
            &track,
            session.skeleton(),
            SkeletonAnimationVersion::V3GlobalFrames,
            FloatFormat::default(),
        )?;
        Ok(true)
    }

    /// Writes the cage keys as a cage animation file.
    pub fn export_cage_animation(
        &self,
        path: &Path,
        session: &RigSession,
    ) -> Result<bool, KeyError> {
        let Some(track) = self.cage_track(session)? else {
            return Ok(false);
        };
        cagerig::io::write_cage_animation(path, &track, FloatFormat::default())?;
        Ok(true)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rig_open::{RigSource, open_rig};

    fn bar() -> RigSession {
        open_rig(&RigSource::Builtin {
            name: "bar".into(),
            resolution: Some(6),
        })
        .unwrap()
        .session
    }

    #[test]
    fn keys_stay_sorted_and_a_key_at_the_same_time_is_replaced() {
        let s = bar();
        let mut keys = Keys::default();
        keys.set_cage_key(1.0, &s);
        keys.set_cage_key(0.0, &s);
        keys.set_cage_key(0.5, &s);
        assert_eq!(
            keys.cage.iter().map(|k| k.time).collect::<Vec<_>>(),
            [0.0, 0.5, 1.0]
        );
        keys.set_cage_key(0.5, &s);
        assert_eq!(keys.len(Track::Cage), 3);
        assert!(keys.move_key(Track::Cage, 0, 1.0).is_err());
        assert_eq!(keys.move_key(Track::Cage, 0, 2.0).unwrap(), 2);
        assert!(keys.delete(Track::Cage, 1));
        assert_eq!(
            keys.cage.iter().map(|k| k.time).collect::<Vec<_>>(),
            [0.5, 2.0]
        );
        keys.validate(&s).unwrap();
    }

    #[test]
    fn playback_at_a_key_time_gives_back_the_keyed_state() {
        let mut s = bar();
        let mut keys = Keys::default();
        keys.set_skeleton_key(0.0, &s);
        keys.set_cage_key(0.0, &s);
        let rest_mesh0 = s.posed_mesh().to_vec();
        s.rotate_joint(1, DVec3::Z, 0.6).unwrap();
        s.move_rest_cage(&[0, 1], &[DVec3::new(0.0, 0.2, 0.0)])
            .unwrap();
        keys.set_skeleton_key(1.0, &s);
        keys.set_cage_key(1.0, &s);
        let posed1 = s.posed_mesh().to_vec();
        let cage1 = s.rest_cage().to_vec();
        let mut player = keys.player(&s).unwrap().unwrap();
        player.apply(0.0, &mut s).unwrap();
        for (a, b) in s.posed_mesh().iter().zip(&rest_mesh0) {
            assert!(a.distance(*b) < 1e-9);
        }
        player.apply(1.0, &mut s).unwrap();
        for (a, b) in s.rest_cage().iter().zip(&cage1) {
            assert!(a.distance(*b) < 1e-12);
        }
        for (a, b) in s.posed_mesh().iter().zip(&posed1) {
            assert!(a.distance(*b) < 1e-9, "{a} vs {b}");
        }
    }

    #[test]
    fn animation_files_round_trip_through_the_paper_tools_formats() {
        let mut s = bar();
        let mut keys = Keys::default();
        keys.set_skeleton_key(0.0, &s);
        keys.set_cage_key(0.0, &s);
        s.rotate_joint(2, DVec3::Y, 0.4).unwrap();
        s.move_rest_cage(&[3], &[DVec3::new(0.1, 0.0, 0.0)])
            .unwrap();
        keys.set_skeleton_key(2.0, &s);
        keys.set_cage_key(2.0, &s);
        let dir = std::env::temp_dir().join(format!("cagerig-studio-keys-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let skel = dir.join("anim.txt");
        let cage = dir.join("cage_anim.txt");
        assert!(keys.export_skeleton_animation(&skel, &s).unwrap());
        assert!(keys.export_cage_animation(&cage, &s).unwrap());
        let mut back = Keys::default();
        assert_eq!(back.import_skeleton_animation(&skel, &s).unwrap(), 2);
        assert_eq!(back.import_cage_animation(&cage, &s).unwrap(), 2);
        for (a, b) in back.skeleton[1]
            .rotations
            .iter()
            .zip(&keys.skeleton[1].rotations)
        {
            assert!(a.dot(*b).abs() > 1.0 - 1e-9, "{a} vs {b}");
        }
        for (a, b) in back.cage[1].rest_cage.iter().zip(&keys.cage[1].rest_cage) {
            assert!(a.distance(*b) < 1e-5);
        }
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn keys_of_another_rig_are_refused_by_validate() {
        let s = bar();
        let mut keys = Keys::default();
        keys.set_cage_key(0.0, &s);
        keys.cage[0].rest_cage.pop();
        let err = keys.validate(&s).unwrap_err().to_string();
        assert!(err.contains("cage vertices"), "{err}");
    }
}
