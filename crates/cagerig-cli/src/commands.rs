//! The subcommands (thin wrappers over the library).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use cagerig::Warning;
use cagerig::cage_coords::CoordsPrecision;
use cagerig::coords::maxvol;
use cagerig::session::{CageFitSource, FitRows, GivenCageCoords, RigSession, SessionOptions};
use cagerig::skinning::SkinningMethod;
use cagerig::sync::skeleton_updater::JointLocalisation;
use clap::{Args, ValueEnum};
use glam::DVec3;
use serde::Serialize;

use crate::output_dir::StagedDir;
use crate::rig_source::{LoadedRig, RigArgs, load_rig};
use crate::state_files::write_state;

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum SkinningArg {
    Lbs,
    Dqs,
    Cor,
}

impl From<SkinningArg> for SkinningMethod {
    fn from(s: SkinningArg) -> Self {
        match s {
            SkinningArg::Lbs => SkinningMethod::Lbs,
            SkinningArg::Dqs => SkinningMethod::Dqs,
            SkinningArg::Cor => SkinningMethod::Cor,
        }
    }
}

#[derive(Debug, Clone, Copy, ValueEnum, Default)]
pub enum FitRowsArg {
    /// MaxVol rows (shipped `.maxvol` if found, else computed): exact square system.
    #[default]
    Maxvol,
    /// All mesh rows, least squares.
    All,
}

#[derive(Debug, Clone, Copy, ValueEnum, Default)]
pub enum LocalisationArg {
    /// cagerig's articulation-localised prior (default).
    #[default]
    Articulation,
    /// The paper tool's localisation (s = 0.05, ε = 0.01, signed masses).
    ReferenceTool,
}

#[derive(Debug, Clone, Copy, ValueEnum, Default)]
pub enum FitSourceArg {
    /// LBS ghost of the fitted rows drives CageUp (exact loop for DQS/CoR).
    #[default]
    Ghost,
    /// CageUp fits the displayed DQS/CoR mesh (approximate reverse deformer).
    Displayed,
}

#[derive(Debug, Clone, Copy, ValueEnum, Default)]
pub enum PrecisionArg {
    /// Φ as computed (exact; matches the paper tool's outputs to 1e-9).
    #[default]
    F64,
    /// Φ rounded to f32 once: half the memory traffic per frame, invariants still exact for the
    /// rounded Φ, rest mesh moved by ~1e-7 of its size.
    F32,
}

/// Session options shared by `edit` and `animate`.
#[derive(Debug, Clone, Args)]
pub struct SessionArgs {
    /// Mesh rows used by CageUp/CageRev.
    #[arg(long, value_enum, default_value_t)]
    pub fit_rows: FitRowsArg,
    /// Joint localisation of the skeleton updater.
    #[arg(long, value_enum, default_value_t)]
    pub localisation: LocalisationArg,
    /// What CageUp fits with DQS/CoR.
    #[arg(long, value_enum, default_value_t)]
    pub fit_source: FitSourceArg,
    /// Precision of the cage coordinates Φ in the per-frame products M = ΦC.
    #[arg(long, value_enum, default_value_t)]
    pub coords_precision: PrecisionArg,
    /// Keep a cage-weights file's Φ even when it does not reproduce the mesh (M ≠ ΦC, e.g. the
    /// tool's 6 decimals): to compare with the tool. By default such a Φ is recomputed, so that
    /// the first cage edit moves only what it touches.
    #[arg(long)]
    pub keep_file_coords: bool,
}

impl SessionArgs {
    pub fn options(&self) -> SessionOptions {
        SessionOptions {
            localisation: match self.localisation {
                LocalisationArg::Articulation => JointLocalisation::default(),
                LocalisationArg::ReferenceTool => JointLocalisation::reference_tool(),
            },
            fit_rows: match self.fit_rows {
                FitRowsArg::Maxvol => FitRows::MaxVol,
                FitRowsArg::All => FitRows::AllRows,
            },
            fit_source: match self.fit_source {
                FitSourceArg::Ghost => CageFitSource::GhostLbs,
                FitSourceArg::Displayed => CageFitSource::DisplayedMesh,
            },
            cage_coords_precision: match self.coords_precision {
                PrecisionArg::F64 => CoordsPrecision::F64,
                PrecisionArg::F32 => CoordsPrecision::F32,
            },
            given_cage_coords: if self.keep_file_coords {
                GivenCageCoords::Keep
            } else {
                GivenCageCoords::RecomputeIfInexact
            },
            ..SessionOptions::default()
        }
    }
}

pub fn start_session(
    loaded: LoadedRig,
    options: SessionOptions,
) -> anyhow::Result<(RigSession, Vec<Warning>)> {
    let options = SessionOptions {
        allow_mesh_outside_cage: loaded.allow_outside_cage,
        ..options
    };
    let (session, mut warnings) =
        RigSession::new(loaded.parts, options).context("assembling the rig")?;
    let mut all = loaded.warnings;
    all.append(&mut warnings);
    Ok((session, all))
}

// ----- info ----------------------------------------------------------------------------------

#[derive(Serialize)]
struct InfoReport {
    rig: String,
    vertices: usize,
    triangles: usize,
    joints: usize,
    cage_vertices: usize,
    cage_triangles: usize,
    max_influences: usize,
    files: Vec<FileUse>,
    warnings: Vec<String>,
    /// The cage validator's checks and figures for this mesh (margin required: none).
    cage_checks: Option<cagerig::cage_gen::CageReport>,
}

#[derive(Clone, Serialize)]
pub struct FileUse {
    pub role: String,
    pub path: PathBuf,
}

pub fn info(rig: &RigArgs, json: bool) -> anyhow::Result<()> {
    let loaded = load_rig(rig, !json, false)?;
    let p = &loaded.parts;
    let mut warnings: Vec<String> = loaded.warnings.iter().map(|w| w.to_string()).collect();
    let cage_check = cagerig::cage::validate_cage(p.cage.clone());
    match &cage_check {
        Ok((_, w)) => warnings.extend(w.iter().map(|w| w.to_string())),
        Err(e) => warnings.push(format!("the cage is unusable: {e}")),
    }
    let report = InfoReport {
        rig: loaded.name.clone(),
        vertices: p.mesh.num_vertices(),
        triangles: p.mesh.num_triangles(),
        joints: p.skeleton.len(),
        cage_vertices: p.cage.num_vertices(),
        cage_triangles: p.cage.num_triangles(),
        max_influences: p.skin_weights.max_influences(),
        files: loaded.files.clone(),
        warnings,
        cage_checks: cage_check
            .is_ok()
            .then(|| crate::cage::validate_rig_cage(&p.cage, &p.mesh)),
    };
    if json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        println!("rig            {}", report.rig);
        println!(
            "mesh           {} vertices, {} triangles",
            report.vertices, report.triangles
        );
        println!(
            "skeleton       {} joints (at most {} influences per vertex)",
            report.joints, report.max_influences
        );
        println!(
            "cage           {} vertices, {} triangles",
            report.cage_vertices, report.cage_triangles
        );
        for f in &report.files {
            println!("file           {:<14} {}", f.role, f.path.display());
        }
        if let Some(checks) = &report.cage_checks {
            println!(
                "cage distance  min {:.3} %, mean {:.3} % of the diagonal",
                100.0 * checks.min_distance_fraction,
                100.0 * checks.mean_distance_fraction
            );
            crate::cage::print_checks(checks);
        }
        if report.warnings.is_empty() {
            println!("warnings       none");
        }
        for w in &report.warnings {
            println!("warning        {w}");
        }
    }
    Ok(())
}

// ----- coords / maxvol -----------------------------------------------------------------------

pub fn coords(rig: &RigArgs, out: &Path, fixed6: bool) -> anyhow::Result<()> {
    let mut loaded = load_rig(rig, true, false)?;
    for w in &loaded.warnings {
        eprintln!("warning: {w}");
    }
    let t = Instant::now();
    let phi = crate::rig_source::compute_coords_with_progress(&loaded.parts, true)?;
    let elapsed = t.elapsed();
    let format = if fixed6 {
        cagerig::io::text::FloatFormat::TOOL
    } else {
        cagerig::io::text::FloatFormat::RoundTrip
    };
    cagerig::io::cage_weights::write_cage_weights(out, &phi, format)?;
    loaded.parts.cage_coords = Some(phi);
    println!(
        "mean value coordinates: {} vertices × {} cage vertices in {:.1} ms, written to {}",
        loaded.parts.mesh.num_vertices(),
        loaded.parts.cage.num_vertices(),
        elapsed.as_secs_f64() * 1e3,
        out.display()
    );
    Ok(())
}

#[derive(Serialize)]
struct MaxvolReport {
    rows: Vec<usize>,
    log_abs_det: f64,
    milliseconds: f64,
    shipped: Option<ShippedMaxvol>,
}

#[derive(Serialize)]
struct ShippedMaxvol {
    path: PathBuf,
    log_abs_det: f64,
}

pub fn maxvol(rig: &RigArgs, out: &Path, json: bool) -> anyhow::Result<()> {
    let loaded = load_rig(rig, !json, true)?;
    for w in &loaded.warnings {
        eprintln!("warning: {w}");
    }
    let phi = match &loaded.parts.cage_coords {
        Some(phi) => phi.clone(),
        None => crate::rig_source::compute_coords_with_progress(&loaded.parts, !json)?,
    };
    let t = Instant::now();
    let selection = maxvol::select_maxvol_rows(&phi)?;
    let ms = t.elapsed().as_secs_f64() * 1e3;
    cagerig::io::maxvol::write_maxvol(out, &selection.rows)?;
    let shipped = match (&loaded.parts.maxvol_rows, &loaded.maxvol_path) {
        (Some(rows), Some(path)) => Some(ShippedMaxvol {
            path: path.clone(),
            log_abs_det: maxvol::log_abs_det_of_rows(&phi, rows)?,
        }),
        _ => None,
    };
    let report = MaxvolReport {
        rows: selection.rows,
        log_abs_det: selection.log_abs_det,
        milliseconds: ms,
        shipped,
    };
    if json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        println!(
            "MaxVol: {} rows, log|det| = {:.6} ({ms:.1} ms), written to {}",
            report.rows.len(),
            report.log_abs_det,
            out.display()
        );
        if let Some(s) = &report.shipped {
            println!(
                "shipped selection {}: log|det| = {:.6}",
                s.path.display(),
                s.log_abs_det
            );
        }
    }
    Ok(())
}

// ----- demo ----------------------------------------------------------------------------------

/// Pictures of the demo's steps, kept in memory until the run succeeded; `None` when pictures
/// are off or no graphics adapter exists (then the run goes on without them and says why).
struct DemoPictures {
    maker: Option<crate::pictures::PictureMaker>,
    images: Vec<(String, cagerig_render::RgbaImage)>,
    /// The current pose after each step, for `sequence.png`.
    sequence: Option<cagerig_render::RgbaImage>,
}

impl DemoPictures {
    fn new(enabled: bool) -> Self {
        let maker = enabled.then(|| crate::pictures::PictureMaker::new(Default::default()));
        let maker = match maker {
            Some(Ok(maker)) => Some(maker),
            Some(Err(e)) => {
                println!("warning: no pictures: {e:#}");
                None
            }
            None => None,
        };
        Self {
            maker,
            images: Vec::new(),
            sequence: None,
        }
    }

    fn add(&mut self, name: &str, session: &RigSession) -> anyhow::Result<()> {
        if let Some(maker) = &mut self.maker {
            let camera = maker.camera(session, 0.0);
            let image = maker.picture(session, &camera)?;
            self.images.push((format!("{name}.png"), image));
            // The current pose alone, appended to the sequence strip.
            let both = maker.options;
            maker.options.view = crate::pictures::ViewArg::Current;
            maker.options.size = (560, 560);
            let camera = maker.camera(session, 0.0);
            let current = maker.picture(session, &camera);
            maker.options = both;
            let current = current?;
            self.sequence = Some(match self.sequence.take() {
                Some(strip) => cagerig_render::RgbaImage::side_by_side(&strip, &current, 4),
                None => current,
            });
        }
        Ok(())
    }

    /// Puts the pictures into the staged output; returns the names written.
    fn write_staged(&self, staged: &mut StagedDir) -> anyhow::Result<Vec<String>> {
        let mut names = Vec::new();
        let strip = self
            .sequence
            .iter()
            .map(|s| ("sequence.png".to_string(), s));
        for (name, image) in self.images.iter().map(|(n, i)| (n.clone(), i)).chain(strip) {
            let png = image
                .to_png()
                .map_err(|e| anyhow::anyhow!("encoding {name}: {e}"))?;
            staged.write(&name, &|w| w.write_all(&png))?;
            names.push(name);
        }
        Ok(names)
    }
}

pub fn demo(
    builtin: &str,
    resolution: Option<usize>,
    out: &Path,
    pictures: bool,
) -> anyhow::Result<()> {
    let args = RigArgs {
        mesh: None,
        cage: None,
        builtin: Some(builtin.to_string()),
        resolution,
        skin: None,
        allow_outside_cage: false,
    };
    let (vertices, cage_vertices) = cagerig::memory_estimate::builtin_size(builtin, resolution);
    cagerig::memory_estimate::check_fits(
        &format!("demo --builtin {builtin}"),
        vertices,
        cage_vertices,
    )?;
    let t = Instant::now();
    let loaded = load_rig(&args, true, true)?;
    let (mut s, warnings) = start_session(loaded, SessionOptions::default())?;
    println!(
        "loaded built-in rig {builtin:?}: {} vertices, {} joints, {} cage vertices ({:.1} ms incl. Φ, MaxVol, Ψ)",
        s.rest_mesh().len(),
        s.skeleton().len(),
        s.rest_cage().len(),
        t.elapsed().as_secs_f64() * 1e3
    );
    for w in &warnings {
        println!("warning: {w}");
    }
    // The output folder is complete or absent: files go to a staging folder renamed to `out`
    // at the end; an earlier demo's output there is replaced (the demo writes only its own
    // state files and pictures, and a folder holding anything else is refused).
    let mut staged = StagedDir::create(out, true)?;
    let mut pictures = DemoPictures::new(pictures);
    write_state(&mut staged, "0_loaded", &s)?;
    pictures.add("0_loaded", &s)?;
    let (lo, hi) = cagerig::mesh::bounding_box(s.rest_cage());
    let centre = (lo + hi) * 0.5;
    let size = (hi - lo).length();

    // 1. Bend with the skeleton: rotate the middle joint.
    let joint = s.skeleton().len() / 2;
    let t = Instant::now();
    s.rotate_joint(joint, DVec3::Z, 60f64.to_radians())?;
    println!(
        "1. skeleton edit: joint {joint} ({}) +60° about Z → M', C' synced in {:.3} ms",
        s.skeleton().joint(joint).name,
        t.elapsed().as_secs_f64() * 1e3
    );
    write_state(&mut staged, "1_bend", &s)?;
    pictures.add("1_bend", &s)?;

    // 2. Inflate with the rest cage: push the cage vertices on the far half outwards.
    let (verts, offsets): (Vec<usize>, Vec<DVec3>) = s
        .rest_cage()
        .iter()
        .enumerate()
        .filter(|(_, c)| c.x > centre.x)
        .map(|(k, c)| {
            let mut radial = *c - centre;
            radial.x = 0.0;
            (k, radial.normalize_or_zero() * 0.08 * size)
        })
        .unzip();
    let t = Instant::now();
    s.move_rest_cage(&verts, &offsets)?;
    println!(
        "2. rest-cage edit: inflated {} cage vertices → M, S, S', M', C' synced in {:.3} ms",
        verts.len(),
        t.elapsed().as_secs_f64() * 1e3
    );
    write_state(&mut staged, "2_inflate", &s)?;
    pictures.add("2_inflate", &s)?;

    // 3. Grab the current cage: pull the vertex farthest along +X.
    let far = s
        .posed_cage()
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.x.total_cmp(&b.1.x))
        .map(|(k, _)| k)
        .unwrap_or(0);
    let target = s.posed_cage()[far] + DVec3::new(0.0, 0.1 * size, 0.0);
    let t = Instant::now();
    s.move_posed_cage(&[far], &[DVec3::new(0.0, 0.1 * size, 0.0)])?;
    println!(
        "3. current-cage grab: vertex {far} → C (CageRev refactor + solve), full loop synced in {:.3} ms; landed {:.2e} from target",
        t.elapsed().as_secs_f64() * 1e3,
        s.posed_cage()[far].distance(target)
    );
    write_state(&mut staged, "3_grab", &s)?;
    pictures.add("3_grab", &s)?;
    let picture_names = pictures.write_staged(&mut staged)?;
    let n = staged.finish()?;
    println!("{n} files written to {}", out.display());
    for name in picture_names {
        let what = if name == "sequence.png" {
            "current pose after each step, left to right"
        } else {
            "rest pose left, current pose right"
        };
        println!("picture ({what}): {}", out.join(name).display());
    }
    Ok(())
}

// ----- subdivide -----------------------------------------------------------------------------

pub fn subdivide(rig: &RigArgs, levels: usize, out: &Path, name: &str) -> anyhow::Result<()> {
    crate::rig_source::subdivide_and_write(rig, levels, out, name)
}
