//! The glTF node hierarchy: parents, local transforms (`matrix` or TRS), world transforms.

use std::path::Path;

use glam::{DAffine3, DMat4, DQuat, DVec3};

use crate::error::{FormatError, invalid};

/// A node's local transform as written in the file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NodeLocal {
    /// `matrix` (may not be animated).
    Matrix(DAffine3),
    /// `translation`, `rotation`, `scale` (each may be animated).
    Trs {
        /// Translation T.
        translation: DVec3,
        /// Rotation R (unit quaternion).
        rotation: DQuat,
        /// Scale S (per axis).
        scale: DVec3,
    },
}

impl NodeLocal {
    /// The local transform as an affine map (T · R · S for TRS).
    pub fn affine(&self) -> DAffine3 {
        match *self {
            NodeLocal::Matrix(m) => m,
            NodeLocal::Trs {
                translation,
                rotation,
                scale,
            } => DAffine3::from_scale_rotation_translation(scale, rotation, translation),
        }
    }
}

/// Parents, rest locals and a parents-first order of every node.
#[derive(Debug, Clone)]
pub struct NodeTree {
    /// Parent node index of every node, `None` for a root.
    pub parent: Vec<Option<usize>>,
    /// Local transform of every node as written in the file.
    pub rest_local: Vec<NodeLocal>,
    /// Every node, parents before children.
    pub order: Vec<usize>,
}

/// 4×4 column-major matrix → affine, refusing a projective bottom row or non-finite entries.
pub fn affine_from_cols(m: [f64; 16], path: &Path, element: &str) -> Result<DAffine3, FormatError> {
    if m.iter().any(|x| !x.is_finite()) {
        return Err(invalid(path, element, "matrix has a non-finite entry"));
    }
    let bottom = [m[3], m[7], m[11], m[15]];
    if (bottom[0].abs() + bottom[1].abs() + bottom[2].abs() + (bottom[3] - 1.0).abs()) > 1e-6 {
        return Err(invalid(
            path,
            element,
            format!("matrix bottom row is {bottom:?}, expected [0, 0, 0, 1] (affine)"),
        ));
    }
    Ok(DAffine3::from_mat4(DMat4::from_cols_array(&m)))
}

impl NodeTree {
    /// Reads the node hierarchy of `document`. Fails (naming `path` and the node) on a node with
    /// two parents, a cycle, or a non-finite or projective transform.
    pub fn new(document: &gltf::Document, path: &Path) -> Result<Self, FormatError> {
        let n = document.nodes().len();
        let mut parent = vec![None; n];
        let mut rest_local = Vec::with_capacity(n);
        for node in document.nodes() {
            let element = format!("node {}", node.index());
            for child in node.children() {
                if let Some(p) = parent[child.index()] {
                    return Err(invalid(
                        path,
                        &element,
                        format!("lists child {} which already has parent {p}", child.index()),
                    ));
                }
                parent[child.index()] = Some(node.index());
            }
            let local = match node.transform() {
                gltf::scene::Transform::Matrix { matrix } => {
                    let flat: Vec<f64> = matrix.iter().flatten().map(|&x| x as f64).collect();
                    let mut cols = [0.0; 16];
                    cols.copy_from_slice(&flat);
                    NodeLocal::Matrix(affine_from_cols(cols, path, &element)?)
                }
                gltf::scene::Transform::Decomposed {
                    translation,
                    rotation,
                    scale,
                } => {
                    let t = DVec3::from(translation.map(f64::from));
                    let [x, y, z, w] = rotation.map(f64::from);
                    let r = DQuat::from_xyzw(x, y, z, w);
                    let s = DVec3::from(scale.map(f64::from));
                    if !t.is_finite() || !r.is_finite() || !s.is_finite() || r.length() < 1e-6 {
                        return Err(invalid(
                            path,
                            &element,
                            "translation/rotation/scale is not finite, or the rotation is zero",
                        ));
                    }
                    NodeLocal::Trs {
                        translation: t,
                        rotation: r.normalize(),
                        scale: s,
                    }
                }
            };
            rest_local.push(local);
        }
        // Parents-first order; a node never reached from a root sits on a cycle.
        let mut order: Vec<usize> = (0..n).filter(|&i| parent[i].is_none()).collect();
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); n];
        for (i, p) in parent.iter().enumerate() {
            if let Some(p) = p {
                children[*p].push(i);
            }
        }
        let mut k = 0;
        while k < order.len() {
            order.extend(children[order[k]].iter().copied());
            k += 1;
        }
        if order.len() != n {
            let stuck = (0..n).find(|i| !order.contains(i)).unwrap_or(0);
            return Err(invalid(
                path,
                format!("node {stuck}"),
                "is its own ancestor: the node hierarchy has a cycle",
            ));
        }
        Ok(Self {
            parent,
            rest_local,
            order,
        })
    }

    /// World transforms of all nodes from their locals.
    pub fn globals(&self, locals: &[DAffine3], out: &mut [DAffine3]) {
        for &i in &self.order {
            out[i] = match self.parent[i] {
                Some(p) => out[p] * locals[i],
                None => locals[i],
            };
        }
    }

    /// Rest locals as affines.
    pub fn rest_affines(&self) -> Vec<DAffine3> {
        self.rest_local.iter().map(NodeLocal::affine).collect()
    }

    /// Whether `ancestor` is a strict ancestor of `node`.
    pub fn is_ancestor(&self, ancestor: usize, node: usize) -> bool {
        let mut k = self.parent[node];
        while let Some(p) = k {
            if p == ancestor {
                return true;
            }
            k = self.parent[p];
        }
        false
    }
}
