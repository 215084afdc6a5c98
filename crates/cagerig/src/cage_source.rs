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
    CageGenError, CageOptions, CageRig, CageTarget, Check, GeneratedCage, generate_rig_cage,
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
    /// The cage that generating would give, made beforehand for this character and these
    /// options (the web page generates it off the page's thread): used in place of generating.
    /// Only with `generate`.
    pub generated: Option<&'a GeneratedCage>,
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
    /// A cage was generated, but the rig could not use one at any size tried.
    #[error("{}: no usable cage could be generated: {reason}", character.display())]
    Unusable {
        /// The character file.
        character: PathBuf,
        /// What is wrong with the mesh, and what to do (the rig check's detail).
        reason: String,
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
        Some(_) if let Some(made) = request.generated => Ok(ChosenCage {
            cage: made.cage.clone(),
            origin: CageOrigin::Generated(Box::new(made.clone())),
        }),
        Some(asked) => {
            let generated =
                generate_usable_cage(character, mesh, rig, asked, RigCheckDepth::WhenInDoubt)?;
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

/// A cage for `mesh` (from `character`, for messages) that a rig can use: generated with the
/// target `asked` lowered to what the mesh allows ([`fit_cage_to_rig`]), then checked as the rig
/// will use it ([`rig_check`], added to the report); a cage the rig could not use is made again
/// with about half as many vertices, down to [`crate::cage_gen::MIN_VERTICES`]. Fails with what
/// is wrong with the mesh and what to do when no size works.
pub fn generate_usable_cage(
    character: &Path,
    mesh: &TriMesh,
    rig: Option<CageRig<'_>>,
    asked: &CageOptions,
    depth: RigCheckDepth,
) -> Result<GeneratedCage, CageSourceError> {
    let mut options = fit_cage_to_rig(asked, mesh);
    loop {
        let mut generated =
            generate_rig_cage(mesh, &options, rig).map_err(|source| CageSourceError::Generate {
                character: character.to_path_buf(),
                source,
            })?;
        let mut check = rig_check(&generated.cage, mesh, depth);
        let nc = generated.cage.num_vertices();
        if check.passed {
            if options.target.vertices() < asked.target.vertices() {
                check.detail = format!(
                    "{nc} vertices instead of the {} asked for, as the rig needs on this mesh: {}",
                    asked.target.vertices(),
                    check.detail
                );
            }
            generated.report.checks.push(check);
            return Ok(generated);
        }
        // Fewer cage vertices need fewer independent rows: try about half as many.
        let fewer = (nc / 2).max(crate::cage_gen::MIN_VERTICES);
        if nc <= crate::cage_gen::MIN_VERTICES || fewer >= options.target.vertices() {
            return Err(CageSourceError::Unusable {
                character: character.to_path_buf(),
                reason: check.detail,
            });
        }
        options.target = CageTarget::Vertices(fewer);
    }
}

/// `options` with the target lowered to what a rig on `mesh` can use: CageUp and CageRev fit
/// the cage on #C MaxVol rows of the mesh, so the cage needs fewer vertices than the mesh has
/// distinct positions; a target above half of them (at least [`crate::cage_gen::MIN_VERTICES`])
/// is lowered to it. So `--auto-cage` on a 24-vertex prism gets a 12-vertex cage, and on a cube
/// whose 24 vertices sit at its 8 corners an 8-vertex one, where the default 100 could not be
/// fitted. The note of the generated cage says so ([`generated_cage_note`]).
pub fn fit_cage_to_rig(options: &CageOptions, mesh: &TriMesh) -> CageOptions {
    let limit = (distinct_positions(mesh) / 2).max(crate::cage_gen::MIN_VERTICES);
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

/// The note that tells the user a cage was generated, with its size and least distance to M,
/// and why it has fewer vertices than asked for when the rig needed that.
pub fn generated_cage_note(generated: &GeneratedCage) -> Warning {
    let lowered = generated
        .report
        .checks
        .iter()
        .find(|c| c.name == RIG_CHECK && c.detail.contains("instead of"))
        .map(|c| format!("; {}", c.detail))
        .unwrap_or_default();
    Warning::Info {
        message: format!(
            "no cage was found: generated one with {} vertices (least distance to the mesh {:.2} % \
             of its diagonal){lowered}",
            generated.cage.num_vertices(),
            100.0 * generated.report.min_distance_fraction
        ),
    }
}

/// Name of the validator's check of what a rig needs of a cage ([`rig_check`]); defined with
/// the validator's other names ([`crate::cage_gen::CHECK_NAMES`]).
pub use crate::cage_gen::validate::RIG_CHECK;

/// How much [`rig_check`] computes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RigCheckDepth {
    /// Always compute Φ and its MaxVol rows, as the rig will (`cagerig cage`).
    Always,
    /// Only when the mesh is flat or has fewer than [`ROWS_BEYOND_DOUBT`] distinct positions per
    /// cage vertex (a generated cage, before the rig computes Φ itself).
    WhenInDoubt,
}

/// Distinct mesh positions per cage vertex above which a mesh that is not flat is taken to
/// give Φ its #C independent rows without computing them ([`RigCheckDepth::WhenInDoubt`]).
pub const ROWS_BEYOND_DOUBT: usize = 20;

/// A mesh is flat when its thinnest bounding-box side is below this fraction of its diagonal.
const FLAT_FRACTION: f64 = 1e-6;

/// Vertices of `mesh` at distinct positions (vertices split for shading share one).
pub fn distinct_positions(mesh: &TriMesh) -> usize {
    mesh.positions
        .iter()
        .map(|p| p.to_array().map(f64::to_bits))
        .collect::<std::collections::HashSet<_>>()
        .len()
}

/// The validator's check of what a rig needs of `cage` on `mesh` (named [`RIG_CHECK`]):
/// CageUp and CageRev solve for the #C cage vertices on #C MaxVol rows of Φ, so the mesh needs
/// at least #C distinct positions whose mean value coordinates are independent. A failed
/// check's detail says, in a modeller's words, what is wrong with the mesh and what to do.
pub fn rig_check(cage: &TriMesh, mesh: &TriMesh, depth: RigCheckDepth) -> Check {
    let nc = cage.num_vertices();
    let (nv, distinct) = (mesh.num_vertices(), distinct_positions(mesh));
    let (lo, hi) = mesh.bounding_box();
    let thinnest = (hi - lo).min_element() / (hi - lo).length().max(f64::MIN_POSITIVE);
    let flat = thinnest < FLAT_FRACTION;
    let fewer_cage_vertices = format!(
        "ask for fewer cage vertices (at most {}), or give the mesh more vertices \
         (`cagerig subdivide`)",
        (distinct / 2).max(crate::cage_gen::MIN_VERTICES)
    );
    let fail = |detail: String| Check {
        name: RIG_CHECK,
        passed: false,
        detail,
    };
    if distinct < nc {
        let split = if distinct < nv {
            format!(
                "only {distinct} distinct vertex positions ({nv} vertices, several at each \
                 position, as a mesh split for flat shading has)"
            )
        } else {
            format!("only {nv} vertices")
        };
        return fail(format!(
            "the rig fits the cage's {nc} vertices to as many mesh vertices, but the mesh has \
             {split}: {fewer_cage_vertices}"
        ));
    }
    let flat_text = "the mesh is flat (it lies in a plane, with no thickness): a cage's mean \
                     value coordinates cannot tell its vertices apart enough to fit the cage to \
                     them; give the mesh some thickness (e.g. Blender's Solidify modifier) or \
                     rig it with a cage made for it";
    let ok = |detail: String| Check {
        name: RIG_CHECK,
        passed: true,
        detail,
    };
    if depth == RigCheckDepth::WhenInDoubt && !flat && distinct >= ROWS_BEYOND_DOUBT * nc {
        return ok(format!(
            "{distinct} distinct mesh positions for {nc} cage vertices"
        ));
    }
    let singular = match crate::coords::mvc::compute_cage_coords(cage, &mesh.positions, None) {
        Err(e) => Some(format!(
            "its mean value coordinates could not be computed ({e})"
        )),
        Ok(phi) => crate::coords::maxvol::select_maxvol_rows(&phi)
            .err()
            .map(|_| format!("no {nc} of its vertices have independent mean value coordinates")),
    };
    match singular {
        None => ok(format!(
            "{nc} independent MaxVol rows among {distinct} distinct mesh positions"
        )),
        Some(_) if flat => fail(flat_text.to_string()),
        Some(why) => fail(format!(
            "the rig fits the cage's {nc} vertices to {nc} mesh vertices, but {why}: the mesh \
             is too simple for this cage; {fewer_cage_vertices}"
        )),
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
            generated: None,
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
            generated: None,
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
            generated: None,
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
