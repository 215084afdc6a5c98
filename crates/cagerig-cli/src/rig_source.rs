//! Where a rig comes from: files on disk (with companions discovered beside the mesh, as the
//! paper tool does) or a built-in demo rig.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use cagerig::auto_weights::AutoWeightsOptions;
use cagerig::cage_gen::{CageOptions, GeneratedCage};
use cagerig::rig_files::{MissingCage, load_rig_files_with_weights};
use cagerig::session::RigParts;
use cagerig::weights_source::{WeightsSource, apply_weights_source};
use cagerig::{CageCoords, Warning};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};

/// Rig selection shared by the subcommands: a MESH file or `--builtin NAME`, exactly one.
#[derive(Debug, Clone, Args)]
#[group(skip)]
#[command(group(
    clap::ArgGroup::new("rig_source")
        .required(true)
        .multiple(false)
        .args(["mesh", "builtin"])
))]
pub struct RigArgs {
    /// Character mesh (OBJ), or a skinned character in glTF 2.0 (`.glb`/`.gltf`) or FBX (`.fbx`).
    /// OBJ companions are discovered beside it: `<stem>.skt`, `<stem>.skw`,
    /// `<stem>_corWeights.txt`, `<stem>_dqBlendWeights.txt`, `<stem>_cage.obj`; beside the cage
    /// `<cage>_cageWeights.txt`, `<cage>.maxvol` (or `<stem>_maxvol.txt`).
    pub mesh: Option<PathBuf>,
    /// Cage (OBJ); default `<stem>_cage.obj` beside the mesh (glTF/FBX: a cage node in the file).
    #[arg(long)]
    pub cage: Option<PathBuf>,
    /// glTF/FBX: the skin to import, by name or index (default: the first).
    #[arg(long)]
    pub skin: Option<String>,
    /// Use a built-in demo rig instead of files (bar, bar_irregular, snake).
    #[arg(long)]
    pub builtin: Option<String>,
    /// Mesh resolution parameter of the built-in rig (bar: ring intervals, default 40; snake:
    /// about the vertex count, default 8192).
    #[arg(long, requires = "builtin")]
    pub resolution: Option<usize>,
    /// Accept mesh vertices outside the cage (reported with their count and farthest distance)
    /// instead of failing: mean value coordinates extrapolate there.
    #[arg(long)]
    pub allow_outside_cage: bool,
    /// Skinning weights (`.skw`, cagerig's vertex order and joint indices, as `cagerig weights`
    /// writes them) instead of the character's own.
    #[arg(long, conflicts_with = "auto_weights")]
    pub weights: Option<PathBuf>,
    /// The skeleton (`.skt`) the `--weights` were made for (as given to `cagerig weights
    /// --skeleton`): it replaces the rig's skeleton (an OBJ then needs no `<stem>.skt`). Without
    /// it, `--weights` must fit the rig's own skeleton.
    #[arg(long, requires = "weights")]
    pub skeleton: Option<PathBuf>,
    /// Compute skinning weights (as `cagerig weights` does with its default options, the rig's
    /// cage bounding the volume) instead of using the character's own; an OBJ then needs no
    /// `.skw`.
    #[arg(long)]
    pub auto_weights: bool,
}

impl RigArgs {
    /// Where the weights come from (`--weights`, `--auto-weights`, else the character's).
    pub fn weights_source(&self) -> WeightsSource {
        match (&self.weights, self.auto_weights) {
            (Some(p), _) => WeightsSource::File {
                weights: p.clone(),
                skeleton: self.skeleton.clone(),
            },
            (None, true) => WeightsSource::Automatic(AutoWeightsOptions::default()),
            (None, false) => WeightsSource::Character,
        }
    }
}

/// `--auto-cage` (every command that builds a rig): what to do when the rig has no cage.
#[derive(Debug, Clone, Args)]
pub struct AutoCageArgs {
    /// When the rig has no cage (no `<stem>_cage.obj`, no --cage, no cage node in a glTF/FBX
    /// file), generate one as `cagerig cage` does with its default options (validated), say
    /// so, and write it into --out as generated_cage.obj where the command writes an --out
    /// folder. Without this flag a rig with no cage is an error.
    #[arg(long)]
    pub auto_cage: bool,
    /// Target vertex count of the generated cage.
    #[arg(long, requires = "auto_cage", default_value_t = cagerig::cage_gen::DEFAULT_VERTICES)]
    pub cage_vertices: usize,
    /// Layout of the generated cage, as `cagerig cage --layout`: by the skeleton (limbs kept
    /// apart by the skin's dominant joints, rings of vertices at the articulations) or one
    /// offset surface around the whole skin.
    #[arg(long, requires = "auto_cage", value_parser = crate::session_args::kind_parser::<cagerig::cage_gen::CageLayout>(), default_value = cagerig::cage_gen::CageLayout::default().name())]
    pub cage_layout: cagerig::cage_gen::CageLayout,
}

impl AutoCageArgs {
    /// The generation options, when asked for.
    pub fn options(&self) -> Option<CageOptions> {
        self.auto_cage.then(|| CageOptions {
            layout: self.cage_layout,
            ..cagerig::cage_source::cage_options_with_vertices(self.cage_vertices)
        })
    }
}

/// A file a command read, and what for (`info` lists them).
#[derive(Clone, serde::Serialize)]
pub struct FileUse {
    /// What the file is to the rig: `mesh`, `skeleton`, `cage`, `character`, ….
    pub role: String,
    /// Where it is.
    pub path: PathBuf,
}

/// File name of a generated cage in an output folder.
pub const GENERATED_CAGE_FILE: &str = "generated_cage.obj";

/// Says that the rig's cage was generated (on stderr, beside the other notes), where it will be
/// written (`written_to`), and how it measures.
pub fn report_generated_cage(rig: &str, g: &GeneratedCage, written_to: &Path) {
    let lowered = g
        .report
        .checks
        .iter()
        .find(|c| c.name == cagerig::cage_source::RIG_CHECK && c.detail.contains("instead of"))
        .map(|c| format!("; {}", c.detail))
        .unwrap_or_default();
    eprintln!(
        "note: {rig} has no cage: generated one with {} vertices, {} triangles (validated: \
         margin ≥ {:.2} % of the diagonal, least distance {:.3} %, mean {:.3} %) in {:.2} s{lowered}; \
         it goes into the output with the results, as {}",
        g.report.cage_vertices,
        g.report.cage_faces,
        100.0 * cagerig::cage_gen::DEFAULT_MARGIN,
        100.0 * g.report.min_distance_fraction,
        100.0 * g.report.mean_distance_fraction,
        g.stats.seconds,
        written_to.display()
    );
}

/// Says on stderr that the rig's cage was generated (commands whose output has no place for
/// the cage file: `render`, `export`).
pub fn note_generated_cage(loaded: &LoadedRig) {
    if let Some(g) = &loaded.generated_cage {
        eprintln!(
            "note: {}: {}",
            loaded.name,
            cagerig::cage_source::generated_cage_note(g)
        );
    }
}

/// Writes a generated cage into a staged output folder as [`GENERATED_CAGE_FILE`].
pub fn write_generated_cage(
    staged: &mut crate::output_dir::StagedDir,
    cage: &cagerig::TriMesh,
) -> anyhow::Result<()> {
    Ok(staged.write(GENERATED_CAGE_FILE, &|w| {
        cagerig::io::obj::write_obj_to(
            w,
            &cage.positions,
            &cage.triangles,
            cagerig::io::text::FloatFormat::RoundTrip,
        )
    })?)
}

/// A loaded rig and what was used to build it.
pub struct LoadedRig {
    pub name: String,
    pub parts: RigParts,
    pub files: Vec<FileUse>,
    pub warnings: Vec<Warning>,
    /// Path of the shipped MaxVol selection, when one was found.
    pub maxvol_path: Option<PathBuf>,
    /// Animations of an imported glTF/FBX character (empty otherwise).
    pub animations: Vec<cagerig_formats::ImportedAnimation>,
    /// The imported character's morph targets (empty otherwise).
    pub morph_targets: cagerig_formats::MorphTargets,
    /// `--allow-outside-cage` (passed on to the session).
    pub allow_outside_cage: bool,
    /// The cage generated because the rig had none (`--auto-cage`).
    pub generated_cage: Option<GeneratedCage>,
    /// The skinning method the file says its authoring tool uses (FBX), if any.
    pub file_skinning: Option<cagerig::skinning::SkinningMethod>,
    /// What the importer read from a glTF/FBX file (`None` for OBJ and built-in rigs).
    pub import_summary: Option<cagerig_formats::ImportSummary>,
}

impl LoadedRig {
    /// The cage's file as the user named it, or "the cage of NAME" when it came with the rig.
    pub fn cage_name(&self) -> String {
        self.files.iter().find(|f| f.role == "cage").map_or_else(
            || format!("the cage of {}", self.name),
            |f| f.path.display().to_string(),
        )
    }
}

/// Loads the rig. With `compute_coords`, Φ is computed (with a progress bar when `progress` and
/// stderr is a terminal) if no cage-weights file was found.
pub fn load_rig(args: &RigArgs, progress: bool, compute_coords: bool) -> anyhow::Result<LoadedRig> {
    load_rig_or_generate_cage(args, progress, compute_coords, None, CageCheck::Loader)
}

/// Where a loaded rig's cage is validated: once, by whoever uses it first.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CageCheck {
    /// By the loader ([`cagerig::cage_enclosure::validate_cage_for_mesh`]): the command uses the
    /// cage without a session (`info`, `coords`, `maxvol`, `subdivide`, `bench`).
    Loader,
    /// By the session the command opens ([`crate::session_args::start_session`], which words
    /// the session's cage errors with the cage file's name).
    Session,
}

/// The rig of a command that builds one from files or a built-in and may generate its cage
/// (`edit`, `animate`, `export`, `render`, `subdivide`): the rig's sources and `--auto-cage`.
#[derive(Debug, Clone, Args)]
pub struct RigInputArgs {
    #[command(flatten)]
    pub rig: RigArgs,
    #[command(flatten)]
    pub auto_cage: AutoCageArgs,
}

impl RigInputArgs {
    /// The rig of a command that opens a session (`edit`, `animate`, `export`, `render`):
    /// loaded with a progress bar and its cage generated under `--auto-cage`; the session
    /// computes the coordinates of the kind it binds with
    /// ([`crate::session_args::start_session`]).
    pub fn load_for_session(&self) -> anyhow::Result<LoadedRig> {
        load_rig_or_generate_cage(
            &self.rig,
            true,
            false,
            self.auto_cage.options(),
            CageCheck::Session,
        )
    }
}

/// [`load_rig`]; when the rig has no cage and `auto_cage` gives options, one is generated
/// ([`LoadedRig::generated_cage`]) instead of failing.
pub fn load_rig_or_generate_cage(
    args: &RigArgs,
    progress: bool,
    compute_coords: bool,
    auto_cage: Option<CageOptions>,
    cage_check: CageCheck,
) -> anyhow::Result<LoadedRig> {
    let weights = args.weights_source();
    let bar = crate::weights_progress::DelayedBar::new();
    let progress_bar = |p| {
        if progress {
            bar.update(p);
        }
    };
    // OBJ rigs take the weights source in the loader (their `.skw` is then not needed).
    let interchange = match (&args.builtin, &args.mesh) {
        (None, Some(mesh)) => crate::interchange::is_interchange(mesh)?,
        _ => false,
    };
    let obj_files = args.builtin.is_none() && args.mesh.is_some() && !interchange;
    let mut loaded = match (&args.builtin, &args.mesh) {
        (Some(name), _) => {
            let (vertices, cage_vertices) =
                cagerig::memory_estimate::builtin_size(name, args.resolution);
            cagerig::memory_estimate::check_fits(
                &format!(
                    "--builtin {name} --resolution {}",
                    args.resolution.unwrap_or_default()
                ),
                vertices,
                cage_vertices,
            )?;
            let rig = cagerig::demo::builtin(name, args.resolution)
                .with_context(|| format!("building the built-in rig {name:?}"))?;
            LoadedRig {
                name: format!("builtin:{name}"),
                parts: RigParts::new(rig.mesh, rig.skeleton, rig.skin_weights, rig.cage),
                files: Vec::new(),
                warnings: Vec::new(),
                maxvol_path: None,
                animations: Vec::new(),
                morph_targets: Default::default(),
                allow_outside_cage: args.allow_outside_cage,
                generated_cage: None,
                file_skinning: None,
                import_summary: None,
            }
        }
        (None, Some(mesh)) if interchange => LoadedRig {
            allow_outside_cage: args.allow_outside_cage,
            ..crate::interchange::load_interchange(
                mesh,
                args.cage.as_deref(),
                args.skin.as_deref(),
                auto_cage,
            )?
        },
        (None, Some(mesh)) => load_files(
            mesh,
            args.cage.as_deref(),
            args.allow_outside_cage,
            auto_cage,
            &weights,
            &progress_bar,
        )?,
        (None, None) => bail!("give a mesh file or --builtin NAME"),
    };
    if !obj_files {
        let file_skeleton: Vec<String> = loaded
            .parts
            .skeleton
            .joints()
            .iter()
            .map(|j| j.name.clone())
            .collect();
        let applied = apply_weights_source(
            &weights,
            &mut loaded.parts,
            &loaded.name,
            &loaded.name,
            &progress_bar,
        )?;
        loaded.warnings.extend(applied.warnings);
        loaded
            .files
            .extend(applied.files.into_iter().map(|(role, path)| FileUse {
                role: role.into(),
                path,
            }));
        drop_animations_of_another_skeleton(&mut loaded, &file_skeleton, &weights);
    }
    bar.finish();
    match cage_check {
        CageCheck::Loader => {
            let (cage, cage_warnings) = cagerig::cage_enclosure::validate_cage_for_mesh(
                std::mem::take(&mut loaded.parts.cage),
                &loaded.parts.mesh.positions,
                args.allow_outside_cage,
            )
            .map_err(|e| anyhow::anyhow!("{}: {e}", loaded.cage_name()))?;
            loaded.parts.cage = cage;
            loaded.warnings.extend(cage_warnings);
        }
        CageCheck::Session => {}
    }
    if compute_coords && loaded.parts.cage_coords.is_none() {
        loaded.parts.cage_coords = Some(compute_coords_with_progress(&loaded.parts, progress)?);
    }
    Ok(loaded)
}

/// The file's animations animate its own skeleton (`file_skeleton`, joint names): when the
/// skeleton paired with `--weights` has other joints, they are left out, with a note.
fn drop_animations_of_another_skeleton(
    loaded: &mut LoadedRig,
    file_skeleton: &[String],
    weights: &WeightsSource,
) {
    let Some(paired) = weights.paired_skeleton() else {
        return;
    };
    let same = loaded.parts.skeleton.len() == file_skeleton.len()
        && loaded
            .parts
            .skeleton
            .joints()
            .iter()
            .zip(file_skeleton)
            .all(|(j, name)| j.name == *name);
    if same || loaded.animations.is_empty() {
        return;
    }
    loaded.warnings.push(Warning::Note {
        message: format!(
            "{}: its {} animations animate its own skeleton ({} joints), not {} ({} joints): \
             they are left out",
            loaded.name,
            loaded.animations.len(),
            file_skeleton.len(),
            paired.display(),
            loaded.parts.skeleton.len()
        ),
    });
    loaded.animations.clear();
}

fn load_files(
    mesh: &Path,
    cage: Option<&Path>,
    allow_outside_cage: bool,
    auto_cage: Option<CageOptions>,
    weights: &WeightsSource,
    progress: &(dyn Fn(cagerig::auto_weights::Progress) + Sync),
) -> anyhow::Result<LoadedRig> {
    let missing_cage = auto_cage.map_or(MissingCage::Fail, MissingCage::Generate);
    let rig =
        load_rig_files_with_weights(mesh, cage, missing_cage, weights, progress).map_err(|e| {
            let cage_missing = matches!(
                &e,
                cagerig::weights_source::WeightsSourceError::Read(cagerig::io::ParseError::Io {
                    message,
                    ..
                }) if message.starts_with("no cage found")
            );
            let weights_missing = matches!(
                &e,
                cagerig::weights_source::WeightsSourceError::Read(cagerig::io::ParseError::Io {
                    message,
                    ..
                }) if message.starts_with("no skinning weights found")
            );
            if auto_cage.is_none() && cage_missing {
                anyhow::anyhow!("{e}; or pass --auto-cage to generate one")
            } else if weights_missing {
                anyhow::anyhow!(
                    "{e}; or pass --weights FILE.skw, or --auto-weights to compute them"
                )
            } else {
                e.into()
            }
        })?;
    Ok(LoadedRig {
        name: mesh.display().to_string(),
        files: rig
            .files
            .into_iter()
            .map(|(role, path)| FileUse {
                role: role.to_string(),
                path,
            })
            .collect(),
        parts: rig.parts,
        warnings: rig.warnings,
        maxvol_path: rig.maxvol_path,
        animations: Vec::new(),
        morph_targets: Default::default(),
        allow_outside_cage,
        generated_cage: rig.generated_cage,
        file_skinning: None,
        import_summary: None,
    })
}

/// A progress bar over the `num_vertices` vertices of a coordinates computation named `what`,
/// when `progress` is on, stderr is a terminal and the mesh is big enough to wait for.
pub fn coords_progress_bar(num_vertices: usize, progress: bool, what: &str) -> Option<ProgressBar> {
    (progress && std::io::stderr().is_terminal() && num_vertices > 20_000).then(|| {
        let bar = ProgressBar::new(num_vertices as u64);
        bar.set_style(
            ProgressStyle::with_template(&format!("{what} {{bar:40}} {{pos}}/{{len}} {{eta}}"))
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        bar
    })
}

/// Mean value coordinates of the rest mesh w.r.t. the rest cage, with a progress bar on a
/// terminal.
pub fn compute_coords_with_progress(
    parts: &RigParts,
    progress: bool,
) -> anyhow::Result<CageCoords> {
    let n = parts.mesh.num_vertices();
    let bar = coords_progress_bar(n, progress, "mean value coordinates");
    let report = |done: usize| {
        if let Some(b) = &bar {
            b.set_position(done as u64);
        }
    };
    let phi = cagerig::coords::mvc::compute_cage_coords(
        &parts.cage,
        &parts.mesh.positions,
        Some(&report),
    )
    .context("computing mean value coordinates")?;
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    Ok(phi)
}
