//! A bind's automatic weights computed somewhere else than the bind itself: the web page hands
//! them to its worker so that the page's thread stays free (the native studio computes them on
//! the bind's own background thread and uses none of this).
//!
//! The bind gives a [`WeightsOffload`] the weights' inputs as a [`WeightsInput`] and a
//! [`WeightsReply`] to answer through. [`WeightsInput`] and [`WeightsOutput`] have a JSON
//! encoding for crossing to another instance of the code (a web worker), where
//! [`WeightsInput::compute`] runs the same [`AutoWeights`] as the bind; each side validates
//! what it decodes.

use std::sync::mpsc::Sender;
use std::sync::{Arc, Mutex};

use cagerig::auto_weights::{AutoWeights, AutoWeightsOptions, Progress, Stage};
use cagerig::{Joint, RigError, Skeleton, SkinWeights, TriMesh, Warning};
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::bind_progress::BindStep;

/// Why an offloaded computation's input or output was refused, or why it failed.
#[derive(Debug, Error)]
pub enum OffloadError {
    /// The JSON could not be written or read.
    #[error("the automatic weights' {what} as JSON: {source}")]
    Json {
        /// Which side: `input` or `output`.
        what: &'static str,
        /// The JSON error.
        source: serde_json::Error,
    },
    /// A mesh, the skeleton or the weights are not valid.
    #[error("the automatic weights' {what}: {source}")]
    Invalid {
        /// What was invalid.
        what: &'static str,
        /// Why.
        source: RigError,
    },
    /// The weights do not fit the bind (`#V × #J`).
    #[error(
        "the automatic weights have {vertices} rows of {joints} joints, expected {expected_vertices} of {expected_joints}"
    )]
    Size {
        vertices: usize,
        joints: usize,
        expected_vertices: usize,
        expected_joints: usize,
    },
    /// The weights could not be computed.
    #[error("automatic weights: {0}")]
    Compute(String),
}

/// What the automatic weights of a bind are computed from: the rest mesh, the new skeleton,
/// the rest cage (its interior is part of the volume) and the options.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct WeightsInput {
    mesh: TriMesh,
    cage: TriMesh,
    joints: Vec<Joint>,
    options: AutoWeightsOptions,
}

/// Computed weights Ω (`#V × #J`, compressed rows) and the computation's warnings, as they
/// cross.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct WeightsOutput {
    num_joints: usize,
    /// Where each vertex's entries start (`#V + 1`).
    row_start: Vec<u32>,
    joints: Vec<u32>,
    weights: Vec<f64>,
    warnings: Vec<Warning>,
}

/// The automatic weights of `mesh` for `skeleton` inside `cage`, with `options`: the one
/// computation both a bind and an offloaded computation run.
pub fn compute_weights(
    options: &AutoWeightsOptions,
    mesh: &TriMesh,
    skeleton: &Skeleton,
    cage: &TriMesh,
    progress: &(dyn Fn(Progress) + Sync),
) -> Result<(SkinWeights, Vec<Warning>), OffloadError> {
    let result = AutoWeights::new(options.clone())
        .map_err(|e| OffloadError::Compute(e.to_string()))?
        .compute_with_progress(mesh, skeleton, Some(cage), progress)
        .map_err(|e| OffloadError::Compute(e.to_string()))?;
    Ok((result.weights, result.report.warnings))
}

impl WeightsInput {
    /// The input of the weights of `mesh` for `skeleton` inside `cage`.
    pub fn new(
        options: &AutoWeightsOptions,
        mesh: &TriMesh,
        skeleton: &Skeleton,
        cage: &TriMesh,
    ) -> Self {
        Self {
            mesh: mesh.clone(),
            cage: cage.clone(),
            joints: skeleton.joints().to_vec(),
            options: options.clone(),
        }
    }

    /// The input as JSON.
    pub fn to_json(&self) -> Result<String, OffloadError> {
        serde_json::to_string(self).map_err(|source| OffloadError::Json {
            what: "input",
            source,
        })
    }

    /// Reads an input written by [`Self::to_json`].
    pub fn from_json(json: &str) -> Result<Self, OffloadError> {
        serde_json::from_str(json).map_err(|source| OffloadError::Json {
            what: "input",
            source,
        })
    }

    /// Validates the input and computes the weights ([`compute_weights`]), reporting
    /// `progress`.
    pub fn compute(
        self,
        progress: &(dyn Fn(Progress) + Sync),
    ) -> Result<WeightsOutput, OffloadError> {
        let invalid = |what| move |source| OffloadError::Invalid { what, source };
        let mesh =
            TriMesh::new(self.mesh.positions, self.mesh.triangles).map_err(invalid("mesh"))?;
        let cage =
            TriMesh::new(self.cage.positions, self.cage.triangles).map_err(invalid("cage"))?;
        let skeleton = Skeleton::new(self.joints).map_err(invalid("skeleton"))?;
        let options = self.options;
        let (weights, warnings) = compute_weights(&options, &mesh, &skeleton, &cage, progress)?;
        let (row_start, joints, values) = weights.csr();
        Ok(WeightsOutput {
            num_joints: weights.num_joints(),
            row_start: row_start.to_vec(),
            joints: joints.to_vec(),
            weights: values.to_vec(),
            warnings,
        })
    }
}

impl WeightsOutput {
    /// The output as JSON.
    pub fn to_json(&self) -> Result<String, OffloadError> {
        serde_json::to_string(self).map_err(|source| OffloadError::Json {
            what: "output",
            source,
        })
    }

    /// Reads an output written by [`Self::to_json`].
    pub fn from_json(json: &str) -> Result<Self, OffloadError> {
        serde_json::from_str(json).map_err(|source| OffloadError::Json {
            what: "output",
            source,
        })
    }

    /// The weights, checked to be Ω of `vertices × joints`, and the computation's warnings.
    pub fn into_weights(
        self,
        vertices: usize,
        joints: usize,
    ) -> Result<(SkinWeights, Vec<Warning>), OffloadError> {
        let rows = self.row_start.len().saturating_sub(1);
        if rows != vertices || self.num_joints != joints {
            return Err(OffloadError::Size {
                vertices: rows,
                joints: self.num_joints,
                expected_vertices: vertices,
                expected_joints: joints,
            });
        }
        let bad = || OffloadError::Compute("the weights' rows are not consistent".into());
        if self.joints.len() != self.weights.len()
            || self.row_start.first() != Some(&0)
            || self.row_start.last().map(|&r| r as usize) != Some(self.joints.len())
            || self.row_start.windows(2).any(|w| w[0] > w[1])
        {
            return Err(bad());
        }
        let mut triplets = Vec::with_capacity(self.joints.len());
        for v in 0..rows {
            let range = self.row_start[v] as usize..self.row_start[v + 1] as usize;
            for k in range {
                triplets.push((v, self.joints[k] as usize, self.weights[k]));
            }
        }
        let (weights, _) =
            SkinWeights::from_triplets(vertices, joints, triplets).map_err(|source| {
                OffloadError::Invalid {
                    what: "weights",
                    source,
                }
            })?;
        Ok((weights, self.warnings))
    }
}

/// A stage of the automatic weights as a number, to report progress across.
pub fn stage_code(stage: Stage) -> u32 {
    match stage {
        Stage::Voxelising => 0,
        Stage::Distances => 1,
        Stage::Weights => 2,
    }
}

/// The stage of [`stage_code`] (`None` for an unknown code).
pub fn stage_of_code(code: u32) -> Option<Stage> {
    match code {
        0 => Some(Stage::Voxelising),
        1 => Some(Stage::Distances),
        2 => Some(Stage::Weights),
        _ => None,
    }
}

/// Where an offloaded computation answers: its progress and, once, its result.
#[derive(Debug)]
pub struct WeightsReply {
    pub(crate) sender: Sender<Result<WeightsOutput, String>>,
    pub(crate) progress: Arc<Mutex<Option<BindStep>>>,
}

impl WeightsReply {
    /// How far the computation is (shown by the bind's progress).
    pub fn report(&self, progress: Progress) {
        if let Ok(mut slot) = self.progress.lock() {
            *slot = Some(BindStep::Weights(progress));
        }
    }

    /// The computation's result (an error is a message for the user); the bind goes on
    /// with it.
    pub fn finish(self, result: Result<WeightsOutput, String>) {
        // The bind may have been dropped meanwhile (its document closed): nobody to tell.
        let _ = self.sender.send(result);
    }
}

/// Computes a bind's automatic weights elsewhere (the web page's worker): takes the input and
/// answers through the reply, later. A reply dropped unanswered fails the bind.
pub trait WeightsOffload: std::fmt::Debug {
    /// Starts computing the weights of `input`.
    fn start(&self, input: WeightsInput, reply: WeightsReply);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The computation's warnings cross to the page as they are: kind and fields, not as text.
    #[test]
    fn warnings_cross_with_their_kind() {
        let warnings = vec![
            Warning::MecFallback {
                joint: 3,
                name: "elbow".into(),
                reason: "no interior point".into(),
            },
            Warning::Note {
                message: "two bones overlap".into(),
            },
        ];
        let output = WeightsOutput {
            num_joints: 2,
            row_start: vec![0, 1, 2],
            joints: vec![0, 1],
            weights: vec![1.0, 1.0],
            warnings: warnings.clone(),
        };
        let json = serde_json::to_string(&output).unwrap();
        let crossed: WeightsOutput = serde_json::from_str(&json).unwrap();
        let (_, received) = crossed.into_weights(2, 2).unwrap();
        assert_eq!(received, warnings);
    }

    #[test]
    fn weights_computed_from_the_encoded_input_are_the_binds() {
        let rig = cagerig::demo::builtin("bar", None).unwrap();
        let options = AutoWeightsOptions::default();
        let (direct, _) =
            compute_weights(&options, &rig.mesh, &rig.skeleton, &rig.cage, &|_| {}).unwrap();
        let json = WeightsInput::new(&options, &rig.mesh, &rig.skeleton, &rig.cage)
            .to_json()
            .unwrap();
        let output = WeightsInput::from_json(&json)
            .unwrap()
            .compute(&|_| {})
            .unwrap()
            .to_json()
            .unwrap();
        let (crossed, _) = WeightsOutput::from_json(&output)
            .unwrap()
            .into_weights(rig.mesh.num_vertices(), rig.skeleton.len())
            .unwrap();
        for v in 0..direct.num_vertices() {
            let (a, b) = (direct.row(v), crossed.row(v));
            assert_eq!(a.0, b.0);
            for (x, y) in a.1.iter().zip(b.1) {
                assert!((x - y).abs() <= 1e-15, "vertex {v}: {x} against {y}");
            }
        }
    }

    #[test]
    fn bad_input_and_output_are_errors() {
        assert!(WeightsInput::from_json("{\"mesh\": 3}").is_err());
        let rig = cagerig::demo::builtin("bar", None).unwrap();
        let options = AutoWeightsOptions::default();
        let mut input = WeightsInput::new(&options, &rig.mesh, &rig.skeleton, &rig.cage);
        input.mesh.triangles.push([0, 1, u32::MAX]);
        assert!(matches!(
            input.compute(&|_| {}),
            Err(OffloadError::Invalid { what: "mesh", .. })
        ));
        let output = WeightsOutput {
            num_joints: 2,
            row_start: vec![0, 1, 5],
            joints: vec![0, 1],
            weights: vec![1.0, 1.0],
            warnings: Vec::new(),
        };
        assert!(
            output.clone().into_weights(2, 2).is_err(),
            "rows beyond the entries"
        );
        assert!(matches!(
            output.into_weights(3, 2),
            Err(OffloadError::Size { .. })
        ));
        let negative = WeightsOutput {
            num_joints: 1,
            row_start: vec![0, 1],
            joints: vec![0],
            weights: vec![-1.0],
            warnings: Vec::new(),
        };
        assert!(negative.into_weights(1, 1).is_err());
    }
}
