//! Animation tracks from files (the paper tool's formats) or from arrays.

use std::path::PathBuf;

use cagerig::Skeleton;
use cagerig::animation::{CageTrack, SkeletonTrack};
use numpy::{PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::convert;
use crate::errors::{RigError, file_error};

fn times_arg(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<f64>> {
    let a = convert::float_array(obj, name)?;
    if a.ndim() != 1 {
        return Err(PyValueError::new_err(format!(
            "{name} must be 1-D (one time per keyframe), got shape {}",
            convert::shape_str(a.shape())
        )));
    }
    Ok(a.readonly().as_array().iter().copied().collect())
}

/// Where a track comes from.
enum TrackSource<'py> {
    /// `(times, keyframes)` arrays.
    Arrays(Bound<'py, PyAny>, Bound<'py, PyAny>),
    File(PathBuf),
}

/// A `(times, keys)` pair or a path.
fn pair_or_path<'py>(obj: &Bound<'py, PyAny>) -> PyResult<TrackSource<'py>> {
    if let Ok((t, k)) = obj.extract::<(Bound<'py, PyAny>, Bound<'py, PyAny>)>() {
        return Ok(TrackSource::Arrays(t, k));
    }
    Ok(TrackSource::File(obj.extract::<PathBuf>().map_err(
        |_| {
            pyo3::exceptions::PyTypeError::new_err(
                "an animation must be a file path or a (times, keyframes) pair of arrays",
            )
        },
    )?))
}

/// Skeleton track: a path (V1/V2/V3 text format) or `(times (K,), locals (K, J, 4, 4))` with
/// local transforms `parent_from_joint` per keyframe.
pub fn skeleton_track(
    py: Python<'_>,
    obj: &Bound<'_, PyAny>,
    skeleton: &Skeleton,
) -> PyResult<SkeletonTrack> {
    match pair_or_path(obj)? {
        TrackSource::File(path) => py
            .detach(|| cagerig::io::read_skeleton_animation(&path, skeleton))
            .map(|(track, _)| track)
            .map_err(file_error),
        TrackSource::Arrays(times, keys) => {
            let times = times_arg(&times, "skeleton times")?;
            let a = convert::float_array(&keys, "skeleton keyframes")?;
            let shape = a.shape().to_vec();
            if shape.len() != 4 || shape[1] != skeleton.len() {
                return Err(PyValueError::new_err(format!(
                    "skeleton keyframes must have shape (K, {}, 4, 4) or (K, {}, 3, 4), got {}",
                    skeleton.len(),
                    skeleton.len(),
                    convert::shape_str(&shape)
                )));
            }
            let flat = a.reshape(vec![shape[0] * shape[1], shape[2], shape[3]])?;
            let all = convert::transforms(flat.as_any(), "skeleton keyframes")?;
            let keys = all
                .chunks(skeleton.len().max(1))
                .map(|c| c.to_vec())
                .collect();
            SkeletonTrack::new(times, keys).map_err(|e| RigError::new_err(e.to_string()))
        }
    }
}

/// Cage track: a path (the tool's cage-animation format) or `(times (K,), offsets (K, #C, 3))`
/// of rest-cage offsets from the cage as loaded.
pub fn cage_track(py: Python<'_>, obj: &Bound<'_, PyAny>, num_cage: usize) -> PyResult<CageTrack> {
    match pair_or_path(obj)? {
        TrackSource::File(path) => py
            .detach(|| cagerig::io::read_cage_animation(&path, num_cage))
            .map_err(file_error),
        TrackSource::Arrays(times, keys) => {
            let times = times_arg(&times, "cage times")?;
            let a = convert::float_array(&keys, "cage keyframes")?;
            let shape = a.shape().to_vec();
            if shape.len() != 3 || shape[1] != num_cage || shape[2] != 3 {
                return Err(PyValueError::new_err(format!(
                    "cage keyframes must have shape (K, {num_cage}, 3), got {}",
                    convert::shape_str(&shape)
                )));
            }
            let flat = a.reshape(vec![shape[0] * shape[1], 3])?;
            let all = convert::points(flat.as_any(), "cage keyframes")?;
            let offsets = all.chunks(num_cage.max(1)).map(|c| c.to_vec()).collect();
            CageTrack::new(times, offsets).map_err(|e| RigError::new_err(e.to_string()))
        }
    }
}
