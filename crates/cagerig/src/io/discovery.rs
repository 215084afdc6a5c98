//! Finding a rig's companion files beside the mesh and cage, named like the paper tool's
//! examples: for `dir/arm.obj` → `arm.skt`, `arm.skw`, `arm_corWeights.txt`,
//! `arm_skelAnim.txt`, `arm_cageAnim.txt` (and cagerig's `arm_dqBlendWeights.txt`); for the cage `dir/arm_cage.obj` →
//! `arm_cage_cageWeights.txt` and the MaxVol rows `arm_cage.maxvol` (or, the name the tool's
//! loader actually looks for, `arm_maxvol.txt` beside the mesh).

use std::path::{Path, PathBuf};

/// The companion files that exist (each `None` when no candidate name exists).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct DiscoveredFiles {
    /// The mesh file given (its stem names the companion files).
    pub mesh: PathBuf,
    /// The cage given, or `<stem>_cage.obj` beside the mesh if it exists.
    pub cage: Option<PathBuf>,
    /// `<stem>.skt`
    pub skeleton: Option<PathBuf>,
    /// `<stem>.skw`
    pub skin_weights: Option<PathBuf>,
    /// `<stem>_corWeights.txt`
    pub cor_weights: Option<PathBuf>,
    /// `<stem>_dqBlendWeights.txt` (cagerig's, for the blended skinning method).
    pub dq_blend_weights: Option<PathBuf>,
    /// `<cage stem>_cageWeights.txt` beside the cage.
    pub cage_coords: Option<PathBuf>,
    /// `<cage stem>.maxvol` beside the cage, else `<stem>_maxvol.txt` beside the mesh.
    pub maxvol: Option<PathBuf>,
    /// `<stem>_skelAnim.txt`, `<stem>_skeletonAnimation.txt` or `<stem>.ska`.
    pub skeleton_animation: Option<PathBuf>,
    /// `<stem>_cageAnim.txt` (or `<cage stem>Anim.txt`).
    pub cage_animation: Option<PathBuf>,
}

impl DiscoveredFiles {
    /// `(role, path)` for every companion, for reports.
    pub fn entries(&self) -> Vec<(&'static str, Option<&Path>)> {
        vec![
            ("mesh", Some(self.mesh.as_path())),
            ("cage", self.cage.as_deref()),
            ("skeleton", self.skeleton.as_deref()),
            ("skin_weights", self.skin_weights.as_deref()),
            ("cor_weights", self.cor_weights.as_deref()),
            ("dq_blend_weights", self.dq_blend_weights.as_deref()),
            ("cage_coords", self.cage_coords.as_deref()),
            ("maxvol", self.maxvol.as_deref()),
            ("skeleton_animation", self.skeleton_animation.as_deref()),
            ("cage_animation", self.cage_animation.as_deref()),
        ]
    }
}

/// `dir/<stem><suffix>` for the first suffix whose file exists.
fn first_existing(dir: &Path, stem: &str, suffixes: &[&str]) -> Option<PathBuf> {
    suffixes
        .iter()
        .map(|s| dir.join(format!("{stem}{s}")))
        .find(|p| p.is_file())
}

fn dir_and_stem(path: &Path) -> (PathBuf, String) {
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    (dir, stem)
}

/// Looks for the companions of `mesh` (and of `cage`, or of `<stem>_cage.obj` if no cage is
/// given). Only checks existence; nothing is read.
pub fn discover(mesh: &Path, cage: Option<&Path>) -> DiscoveredFiles {
    let (dir, stem) = dir_and_stem(mesh);
    let cage = match cage {
        Some(c) => Some(c.to_path_buf()),
        None => first_existing(&dir, &stem, &["_cage.obj"]),
    };
    let mut found = DiscoveredFiles {
        mesh: mesh.to_path_buf(),
        skeleton: first_existing(&dir, &stem, &[".skt"]),
        skin_weights: first_existing(&dir, &stem, &[".skw"]),
        cor_weights: first_existing(&dir, &stem, &["_corWeights.txt"]),
        dq_blend_weights: first_existing(&dir, &stem, &["_dqBlendWeights.txt"]),
        skeleton_animation: first_existing(
            &dir,
            &stem,
            &["_skelAnim.txt", "_skeletonAnimation.txt", ".ska"],
        ),
        cage_animation: first_existing(&dir, &stem, &["_cageAnim.txt"]),
        ..Default::default()
    };
    if let Some(cage_path) = &cage {
        let (cage_dir, cage_stem) = dir_and_stem(cage_path);
        found.cage_coords = first_existing(&cage_dir, &cage_stem, &["_cageWeights.txt"]);
        found.maxvol = first_existing(&cage_dir, &cage_stem, &[".maxvol"]);
        if found.cage_animation.is_none() {
            found.cage_animation = first_existing(&cage_dir, &cage_stem, &["Anim.txt"]);
        }
    }
    if found.maxvol.is_none() {
        found.maxvol = first_existing(&dir, &stem, &["_maxvol.txt"]);
    }
    found.cage = cage;
    found
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_tool_names_and_falls_back() {
        let dir = std::env::temp_dir().join(format!("cagerig_discovery_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for name in [
            "m.obj",
            "m.skt",
            "m_cage.obj",
            "m_cage_cageWeights.txt",
            "m_maxvol.txt",
            "m_dqBlendWeights.txt",
        ] {
            std::fs::write(dir.join(name), b"").unwrap();
        }
        let d = discover(&dir.join("m.obj"), None);
        assert_eq!(d.cage, Some(dir.join("m_cage.obj")));
        assert_eq!(d.skeleton, Some(dir.join("m.skt")));
        assert_eq!(d.skin_weights, None);
        assert_eq!(d.cage_coords, Some(dir.join("m_cage_cageWeights.txt")));
        assert_eq!(d.maxvol, Some(dir.join("m_maxvol.txt")));
        assert_eq!(d.dq_blend_weights, Some(dir.join("m_dqBlendWeights.txt")));
        std::fs::write(dir.join("m_cage.maxvol"), b"").unwrap();
        let d = discover(&dir.join("m.obj"), Some(&dir.join("m_cage.obj")));
        assert_eq!(d.maxvol, Some(dir.join("m_cage.maxvol")));
        let d = discover(&dir.join("m.obj"), Some(&dir.join("other.obj")));
        assert_eq!(d.cage_coords, None);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
