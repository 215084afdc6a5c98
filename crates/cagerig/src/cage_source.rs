//! Where a character's cage C comes from: the one rule every front end (CLI, Python, studio)
//! applies when it opens a character.
//!
//! The rule, in order: the cage OBJ the user gave; else the cage found with the character (a cage
//! node in a glTF/FBX file, or `<stem>_cage.obj` beside an OBJ); else a generated one
//! ([`crate::cage_gen::generate_rig_cage`], laid out by the rig's skeleton when it has one) when
//! the user asked for one; else an error that the front end words in its own terms (an option
//! name, a keyword, a checkbox).

use std::path::{Path, PathBuf};

use thiserror::Error;

use crate::cage_gen::{
    CageGenError, CageOptions, CageRig, CageTarget, GeneratedCage, generate_rig_cage,
};
use crate::error::Warning;
use crate::io::ParseError;
use crate::mesh::TriMesh;

/// What the user asked for about the cage.
#[derive(Debug, Clone, Copy, Default)]
pub struct CageRequest<'a> {
    /// A cage OBJ given explicitly (`--cage`, `cage=`, the Open dialog).
    pub given: Option<&'a Path>,
    /// Generate a cage with these options when none is given or found (`--auto-cage`).
    pub generate: Option<CageOptions>,
}

/// Where the chosen cage came from.
#[derive(Debug, Clone)]
pub enum CageOrigin {
    /// The OBJ the user gave.
    Given(PathBuf),
    /// The cage that came with the character.
    Found,
    /// Generated, with the generator's report.
    Generated(Box<GeneratedCage>),
}

/// The cage of a character and where it came from.
#[derive(Debug, Clone)]
pub struct ChosenCage {
    /// The rest cage C (`#C` vertices, closed triangle mesh), in the character's space.
    pub cage: TriMesh,
    /// Where it came from.
    pub origin: CageOrigin,
}

/// Why no cage could be chosen.
#[derive(Debug, Error)]
pub enum CageSourceError {
    /// The given cage OBJ could not be read.
    #[error(transparent)]
    Read(#[from] ParseError),
    /// No cage was given or found, and generating one was asked for but failed.
    #[error("{}: no cage in the file, and none could be generated: {source}", character.display())]
    Generate {
        /// The character file.
        character: PathBuf,
        /// Why generation failed.
        source: CageGenError,
    },
    /// No cage was given or found, and none was to be generated.
    #[error("{}: no cage was given or found with the character", character.display())]
    Missing {
        /// The character file.
        character: PathBuf,
    },
}

/// Applies the cage-source rule (see the module doc) to `character` (the file, for messages),
/// its skin `mesh` M (`#V`, for generation), its skeleton and weights `rig` (for the skeleton
/// layout of a generated cage; `None` for a mesh without a rig) and the cage `found` with it.
pub fn choose_cage(
    character: &Path,
    mesh: &TriMesh,
    rig: Option<CageRig<'_>>,
    found: Option<TriMesh>,
    request: &CageRequest<'_>,
) -> Result<ChosenCage, CageSourceError> {
    if let Some(path) = request.given {
        let cage = crate::io::obj::read_obj(path)?;
        if cage.num_vertices() == 0 || cage.num_triangles() == 0 {
            // Named here, before any file that belongs to the cage (Φ, MaxVol rows) is read
            // against it and blamed instead.
            return Err(CageSourceError::Read(ParseError::Rig {
                path: path.to_path_buf(),
                source: crate::error::RigError::Invalid(format!(
                    "the cage is empty ({} vertices, {} triangles): expected a closed triangle \
                     mesh around the character",
                    cage.num_vertices(),
                    cage.num_triangles()
                )),
            }));
        }
        return Ok(ChosenCage {
            cage,
            origin: CageOrigin::Given(path.to_path_buf()),
        });
    }
    if let Some(cage) = found {
        return Ok(ChosenCage {
            cage,
            origin: CageOrigin::Found,
        });
    }
    match &request.generate {
        Some(options) => {
            let options = fit_cage_to_rig(options, mesh);
            let generated = generate_rig_cage(mesh, &options, rig).map_err(|source| {
                CageSourceError::Generate {
                    character: character.to_path_buf(),
                    source,
                }
            })?;
            Ok(ChosenCage {
                cage: generated.cage.clone(),
                origin: CageOrigin::Generated(Box::new(generated)),
            })
        }
        None => Err(CageSourceError::Missing {
            character: character.to_path_buf(),
        }),
    }
}

/// `options` with the target lowered to what a rig on `mesh` can use: CageUp and CageRev fit
/// the cage on #C MaxVol rows of the mesh, so the cage needs fewer vertices than the mesh; a
/// target above half the mesh's vertex count (at least [`crate::cage_gen::MIN_VERTICES`]) is
/// lowered to it. So `--auto-cage` on a 24-vertex mesh gets a 12-vertex cage, where the default
/// 100 could not be fitted.
pub fn fit_cage_to_rig(options: &CageOptions, mesh: &TriMesh) -> CageOptions {
    let limit = (mesh.num_vertices() / 2).max(crate::cage_gen::MIN_VERTICES);
    if options.target.vertices() <= limit {
        return *options;
    }
    CageOptions {
        target: CageTarget::Vertices(limit),
        ..*options
    }
}

/// Default [`CageOptions`] aiming at `vertices` cage vertices (the front ends' `--auto-cage N`).
pub fn cage_options_with_vertices(vertices: usize) -> CageOptions {
    CageOptions {
        target: CageTarget::Vertices(vertices),
        ..CageOptions::default()
    }
}

/// The note that tells the user a cage was generated, with its size and least distance to M.
pub fn generated_cage_note(generated: &GeneratedCage) -> Warning {
    Warning::Note {
        message: format!(
            "no cage was found: generated one with {} vertices (least distance to the mesh {:.2} % \
             of its diagonal)",
            generated.cage.num_vertices(),
            100.0 * generated.report.min_distance_fraction
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn octahedron(scale: f64) -> TriMesh {
        let (p, t) = crate::coords::mvc::tests::octahedron([scale; 6]);
        TriMesh::new(p, t).unwrap()
    }

    #[test]
    fn the_found_cage_wins_over_generation_and_nothing_is_an_error() {
        let mesh = octahedron(1.0);
        let found = octahedron(2.0);
        let request = CageRequest {
            given: None,
            generate: Some(cage_options_with_vertices(50)),
        };
        let chosen = choose_cage(
            Path::new("x.glb"),
            &mesh,
            None,
            Some(found.clone()),
            &request,
        )
        .unwrap();
        assert!(matches!(chosen.origin, CageOrigin::Found));
        assert_eq!(chosen.cage.positions, found.positions);
        let err = choose_cage(
            Path::new("x.glb"),
            &mesh,
            None,
            None,
            &CageRequest::default(),
        )
        .unwrap_err();
        assert!(matches!(err, CageSourceError::Missing { .. }), "{err}");
        assert_eq!(
            err.to_string(),
            "x.glb: no cage was given or found with the character"
        );
    }

    /// Regression: an empty cage file was blamed on the cage-weights file read after it.
    #[test]
    fn an_empty_cage_file_is_named() {
        let dir = std::env::temp_dir().join(format!("cagerig-empty-cage-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("empty_cage.obj");
        std::fs::write(&path, "# nothing\n").unwrap();
        let request = CageRequest {
            given: Some(&path),
            generate: None,
        };
        let err = choose_cage(Path::new("x.obj"), &octahedron(1.0), None, None, &request)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("empty_cage.obj") && err.contains("empty"),
            "{err}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_given_cage_that_cannot_be_read_names_its_file() {
        let mesh = octahedron(1.0);
        let request = CageRequest {
            given: Some(Path::new("/nonexistent/cage.obj")),
            generate: None,
        };
        let err = choose_cage(
            Path::new("x.glb"),
            &mesh,
            None,
            Some(octahedron(2.0)),
            &request,
        )
        .unwrap_err();
        assert!(err.to_string().contains("/nonexistent/cage.obj"), "{err}");
    }
}
