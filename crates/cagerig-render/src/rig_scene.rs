//! A [`RigSession`]'s rest pose (M, C, S) or current pose (M', C', S') as a [`Scene`], with
//! optional colour maps: skin weights Ω of a joint, cage coordinates Φ of a cage vertex, or the
//! joint coordinates Ψ of a joint on the cage handles.

use cagerig::session::RigSession;
use glam::DVec3;

use crate::palette::ColorMap;
use crate::scene::{CageLayer, MeshLayer, MeshPositions, Scene, SkeletonLayer};

/// Which of the rig's two poses a view shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pose {
    /// M, C, S.
    Rest,
    /// M', C', S'.
    Current,
}

/// A per-vertex scalar shown as colours.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ColorBy {
    /// No colour map.
    #[default]
    None,
    /// Skin weights Ω[:, j] of joint `j` on the skin (sequential map, [0, 1]).
    JointWeights(usize),
    /// Mean value coordinates Φ[:, k] of cage vertex `k` on the skin (diverging map: they go
    /// negative).
    CageCoords(usize),
    /// Joint coordinates Ψ[j, :] of joint `j` on the cage handles (diverging map).
    JointCageCoords(usize),
    /// How far each cage handle is from the skin shown, over the largest distance of the rest
    /// cage from the rest skin: the usual handle colour up to 1, turning red by
    /// [`REACH_RED`] (the quality of the current cage as a handle; `docs/method.md`).
    CageReach,
}

/// Which layers to draw.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Layers {
    /// The skin (M or M').
    pub mesh: bool,
    /// Skin triangle edges over the surface.
    pub wireframe: bool,
    /// The cage (C or C'): faces, edges and handles.
    pub cage: bool,
    /// The skeleton (S or S'): bones and joints.
    pub skeleton: bool,
    /// Faceted shading of the skin instead of smooth.
    pub flat: bool,
    /// The ground grid with a contact shadow.
    pub ground: bool,
}

impl Default for Layers {
    fn default() -> Self {
        Self {
            mesh: true,
            wireframe: false,
            cage: true,
            skeleton: true,
            flat: false,
            ground: true,
        }
    }
}

/// Scratch data behind a rig's scene (colours, joint positions), reused between frames.
#[derive(Debug, Default)]
pub struct RigSceneData {
    mesh_colors: Vec<[u8; 4]>,
    handle_colors: Vec<[u8; 4]>,
    joints: Vec<DVec3>,
    parents: Vec<Option<usize>>,
    scalars: Vec<f64>,
    /// Cage vertices drawn as marked (e.g. those an edit moved), over any handle colour map.
    pub marked_handles: Vec<usize>,
}

/// Why a colour map cannot be shown.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ColorByError {
    /// The joint index is out of range.
    #[error("joint {index} does not exist: the rig has {count} joints")]
    Joint {
        /// The joint index asked for.
        index: usize,
        /// Number of joints `#J`.
        count: usize,
    },
    /// The cage vertex index is out of range.
    #[error("cage vertex {index} does not exist: the cage has {count} vertices")]
    CageVertex {
        /// The cage vertex index asked for.
        index: usize,
        /// Number of cage vertices `#C`.
        count: usize,
    },
}

impl ColorBy {
    /// Checks the index against the rig.
    pub fn validate(self, session: &RigSession) -> Result<(), ColorByError> {
        let joints = session.skeleton().len();
        let cage = session.rest_cage().len();
        match self {
            ColorBy::None => Ok(()),
            ColorBy::JointWeights(j) | ColorBy::JointCageCoords(j) if j >= joints => {
                Err(ColorByError::Joint {
                    index: j,
                    count: joints,
                })
            }
            ColorBy::CageCoords(k) if k >= cage => Err(ColorByError::CageVertex {
                index: k,
                count: cage,
            }),
            ColorBy::JointWeights(_)
            | ColorBy::JointCageCoords(_)
            | ColorBy::CageCoords(_)
            | ColorBy::CageReach => Ok(()),
        }
    }

    /// The scalar per skin vertex (`#V`) written into `out`, and its map; `None` when this
    /// colours the cage handles or nothing.
    pub fn mesh_scalars(self, session: &RigSession, out: &mut Vec<f64>) -> Option<ColorMap> {
        out.clear();
        match self {
            ColorBy::JointWeights(j) => {
                let weights = session.skin_weights();
                out.extend((0..weights.num_vertices()).map(|v| weights.get(v, j)));
                Some(ColorMap::Sequential { lo: 0.0, hi: 1.0 })
            }
            ColorBy::CageCoords(k) => {
                out.extend_from_slice(session.cage_coords().column(k));
                // Φ[:, k] peaks near cage vertex k and is small elsewhere: the map follows the
                // bulk (90th percentile of |Φ|), the peak saturates.
                Some(ColorMap::diverging_robust(out, PHI_MAP_QUANTILE))
            }
            ColorBy::None | ColorBy::JointCageCoords(_) | ColorBy::CageReach => None,
        }
    }
}

/// The reach ratio at which a handle is drawn fully red ([`ColorBy::CageReach`]).
pub const REACH_RED: f64 = 2.5;
/// Skin vertices a handle's distance is measured against at most (a regular subsample).
const REACH_SAMPLES: usize = 4096;
/// The colour of a handle far from the skin.
const FAR_HANDLE: [u8; 4] = [220, 30, 30, 255];

/// The handle colour of a reach ratio: the usual colour up to 1, [`FAR_HANDLE`] from
/// [`REACH_RED`], blended between.
fn reach_color(ratio: f64) -> [u8; 4] {
    let usual = crate::scene::Style::default().cage_handles;
    let t = ((ratio - 1.0) / (REACH_RED - 1.0)).clamp(0.0, 1.0);
    std::array::from_fn(|i| {
        let (a, b) = (f64::from(usual[i]), f64::from(FAR_HANDLE[i]));
        (a + t * (b - a)).round() as u8
    })
}

/// Distance of each of `points` to the nearest of every `stride`-th skin vertex, into `out`.
fn reach(points: &[DVec3], mesh: &MeshPositions<'_>, out: &mut Vec<f64>) {
    let n = match mesh {
        MeshPositions::F64(m) => m.len(),
        MeshPositions::F32(m) => m.len(),
    };
    let stride = n.div_ceil(REACH_SAMPLES).max(1);
    let at = |v: usize| match mesh {
        MeshPositions::F64(m) => m[v],
        MeshPositions::F32(m) => m[v].as_dvec3(),
    };
    out.clear();
    out.extend(points.iter().map(|p| {
        (0..n)
            .step_by(stride)
            .map(|v| at(v).distance_squared(*p))
            .fold(f64::INFINITY, f64::min)
            .sqrt()
    }));
}

/// Quantile of |Φ[:, k]| that the Φ colour map's ends stand for.
const PHI_MAP_QUANTILE: f64 = 0.9;

/// Colour of the cage handle whose Φ column is shown.
const CHOSEN_HANDLE: [u8; 4] = [25, 30, 60, 255];

/// The colour of marked cage handles ([`RigSceneData::marked_handles`]): magenta, apart from
/// the usual orange handles and the reach map's red.
pub const MARKED_HANDLE: [u8; 4] = [200, 20, 160, 255];

impl RigSceneData {
    /// Empty scratch data.
    pub fn new() -> Self {
        Self::default()
    }

    /// The colour map `color_by` shows on `session` and a legend title (`Ω joint NAME`,
    /// `Φ cage vertex K`, `Ψ joint NAME`); `None` for no colour map or an invalid index.
    pub fn legend(
        &mut self,
        session: &RigSession,
        color_by: ColorBy,
    ) -> Option<(ColorMap, String)> {
        color_by.validate(session).ok()?;
        let joint_name = |j: usize| session.skeleton().joint(j).name.clone();
        match color_by {
            ColorBy::None | ColorBy::CageReach => None,
            ColorBy::JointWeights(j) => color_by
                .mesh_scalars(session, &mut self.scalars)
                .map(|m| (m, format!("Ω {}", joint_name(j)))),
            ColorBy::CageCoords(k) => color_by
                .mesh_scalars(session, &mut self.scalars)
                .map(|m| (m, format!("Φ cage vertex {k}"))),
            ColorBy::JointCageCoords(j) => Some((
                ColorMap::diverging_for(session.skeleton_updater().joint_row(j)),
                format!("Ψ {}", joint_name(j)),
            )),
        }
    }

    /// The scene of `pose`. `color_by` must have passed [`ColorBy::validate`] for this
    /// session (an invalid index draws no colour map).
    pub fn scene<'a>(
        &'a mut self,
        session: &'a RigSession,
        pose: Pose,
        layers: Layers,
        color_by: ColorBy,
    ) -> Scene<'a> {
        self.scene_with_skeleton(session, pose, layers, color_by, None)
    }

    /// [`RigSceneData::scene`] drawing `skeleton` — joint positions (`#J'`, world space) and
    /// their parents — instead of the session's (an editor's skeleton being built); `None`
    /// draws the session's.
    pub fn scene_with_skeleton<'a>(
        &'a mut self,
        session: &'a RigSession,
        pose: Pose,
        layers: Layers,
        color_by: ColorBy,
        skeleton: Option<(&[DVec3], &[Option<usize>])>,
    ) -> Scene<'a> {
        // Both skins come from the session's f32 display path when it is on.
        let (mesh, cage) = match pose {
            Pose::Rest => (
                session.display_rest_mesh().map_or_else(
                    || MeshPositions::F64(session.rest_mesh()),
                    MeshPositions::F32,
                ),
                session.rest_cage(),
            ),
            Pose::Current => (
                session.display_mesh().map_or_else(
                    || MeshPositions::F64(session.posed_mesh()),
                    MeshPositions::F32,
                ),
                session.posed_cage(),
            ),
        };
        self.joints.clear();
        self.parents.clear();
        match (skeleton, pose) {
            (Some((joints, parents)), _) => {
                self.joints.extend_from_slice(joints);
                self.parents.extend_from_slice(parents);
            }
            (None, Pose::Rest) => self.joints.extend(session.rest_joints()),
            (None, Pose::Current) => self.joints.extend(session.posed_joints()),
        }
        if skeleton.is_none() {
            self.parents
                .extend(session.skeleton().joints().iter().map(|j| j.parent));
        }
        let valid = color_by.validate(session).is_ok();
        let mesh_map = if valid {
            color_by.mesh_scalars(session, &mut self.scalars)
        } else {
            None
        };
        self.mesh_colors.clear();
        if let Some(map) = mesh_map {
            self.mesh_colors
                .extend(self.scalars.iter().map(|&s| map.color_u8(s)));
        }
        self.handle_colors.clear();
        match (valid, color_by) {
            (true, ColorBy::JointCageCoords(j)) => {
                let row = session.skeleton_updater().joint_row(j);
                let map = ColorMap::diverging_for(row);
                self.handle_colors
                    .extend(row.iter().map(|&s| map.color_u8(s)));
            }
            (true, ColorBy::CageCoords(k)) => {
                // The chosen cage vertex is marked: dark among the usual handles.
                let usual = crate::scene::Style::default().cage_handles;
                self.handle_colors
                    .extend((0..cage.len()).map(|c| if c == k { CHOSEN_HANDLE } else { usual }));
            }
            (true, ColorBy::CageReach) => {
                reach(
                    session.rest_cage(),
                    &MeshPositions::F64(session.rest_mesh()),
                    &mut self.scalars,
                );
                let rest_reach = self.scalars.iter().copied().fold(0.0, f64::max);
                reach(cage, &mesh, &mut self.scalars);
                self.handle_colors.extend(self.scalars.iter().map(|&d| {
                    reach_color(if rest_reach > 0.0 {
                        d / rest_reach
                    } else {
                        1.0
                    })
                }));
            }
            (true, ColorBy::None | ColorBy::JointWeights(_)) | (false, _) => {}
        }
        if !self.marked_handles.is_empty() {
            if self.handle_colors.is_empty() {
                let usual = crate::scene::Style::default().cage_handles;
                self.handle_colors.resize(cage.len(), usual);
            }
            for &k in &self.marked_handles {
                if let Some(c) = self.handle_colors.get_mut(k) {
                    *c = MARKED_HANDLE;
                }
            }
        }
        Scene {
            mesh: layers.mesh.then_some(MeshLayer {
                positions: mesh,
                triangles: session.mesh_triangles(),
                colors: (!self.mesh_colors.is_empty()).then_some(&self.mesh_colors[..]),
                flat: layers.flat,
                wireframe: layers.wireframe,
                topology_id: Some(session.topology_id()),
            }),
            cage: layers.cage.then_some(CageLayer {
                positions: cage,
                triangles: session.cage_triangles(),
                handle_colors: (!self.handle_colors.is_empty()).then_some(&self.handle_colors[..]),
            }),
            skeleton: layers.skeleton.then_some(SkeletonLayer {
                joints: &self.joints,
                parents: &self.parents,
                joint_colors: None,
            }),
            ground: layers.ground,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cagerig::session::{RigParts, SessionOptions};

    fn bar() -> RigSession {
        let rig = cagerig::demo::builtin("bar", None).unwrap();
        let parts = RigParts::new(rig.mesh, rig.skeleton, rig.skin_weights, rig.cage);
        RigSession::new(parts, SessionOptions::default()).unwrap().0
    }

    fn handle_colors(data: &mut RigSceneData, session: &RigSession) -> Vec<[u8; 4]> {
        let scene = data.scene(
            session,
            Pose::Current,
            Layers::default(),
            ColorBy::CageReach,
        );
        scene.cage.unwrap().handle_colors.unwrap().to_vec()
    }

    #[test]
    fn cage_reach_leaves_handles_at_rest_and_reddens_stray_ones() {
        let mut session = bar();
        let mut data = RigSceneData::new();
        let usual = crate::scene::Style::default().cage_handles;
        // No handle is further from the skin than the rest cage's furthest: at rest, and after
        // a bend (the regularised C' stays on the bar).
        assert!(
            handle_colors(&mut data, &session)
                .iter()
                .all(|&c| c == usual)
        );
        session.rotate_joint(1, DVec3::Z, 0.8).unwrap();
        let bent = handle_colors(&mut data, &session);
        assert!(bent.iter().all(|c| c[1] >= 120), "{bent:?}");
        assert!(ColorBy::CageReach.validate(&session).is_ok());
        assert!(data.legend(&session, ColorBy::CageReach).is_none());
        // The map: usual up to 1, red from REACH_RED, blended between.
        assert_eq!(reach_color(0.3), usual);
        assert_eq!(reach_color(1.0), usual);
        assert_eq!(reach_color(REACH_RED), FAR_HANDLE);
        assert_eq!(reach_color(10.0), FAR_HANDLE);
        let mid = reach_color(0.5 * (1.0 + REACH_RED));
        assert!(mid[1] < usual[1] && mid[1] > FAR_HANDLE[1], "{mid:?}");
    }
}
