//! The session options every rig-building subcommand shares (`--fit-rows`, `--skinning`, …),
//! and starting a session from a loaded rig.

use cagerig::cage_coords::CoordsPrecision;
use cagerig::coords::stretched_normals::FaceTermKind;
use cagerig::session::{
    BindStage, CageFitSource, FitRowsKind, GivenCageCoords, RigSession, SessionOptions,
    UnfittedCagePolicy,
};
use cagerig::skinning::SkinningMethod;
use cagerig::sync::skeleton_updater::LocalisationKind;
use cagerig::{CageFitKind, CoordsKind, NamedKind, Warning};
use clap::Args;

use crate::rig_source::LoadedRig;

/// The value parser of an option naming a [`NamedKind`] (`--skinning`, `--coords`,
/// `--cage-fit`, `--unfitted-cage`): the names and help of `K::ALL` (listed in `--help`), read
/// through `K: FromStr`, the one parser of those names.
pub fn kind_parser<K>() -> impl clap::builder::TypedValueParser<Value = K>
where
    K: NamedKind + Send + Sync,
    K::Err: std::error::Error + Send + Sync + 'static,
{
    use clap::builder::{PossibleValue, TypedValueParser};
    clap::builder::PossibleValuesParser::new(K::ALL.iter().map(|k| {
        let value = PossibleValue::new(k.name());
        match k.help() {
            "" => value,
            help => value.help(help),
        }
    }))
    .try_map(|name| name.parse::<K>())
}

/// Session options shared by `edit` and `animate`.
#[derive(Debug, Clone, Args)]
pub struct SessionArgs {
    /// Cage coordinates: mean value (the paper's linear M = ΦC) or Green (shape-preserving cage
    /// edits; see docs/green-coordinates.md).
    #[arg(long, value_parser = kind_parser::<CoordsKind>(), default_value = "mvc")]
    pub coords: CoordsKind,
    /// How CageUp fits the current cage C' to the posed skin: regularised towards the rest cage
    /// carried by the skeleton, or the paper's fit on the rows alone (Green rigs: Gauss–Newton
    /// on the rows, with or without that regulariser). See docs/method.md.
    #[arg(long, value_parser = kind_parser::<CageFitKind>(), default_value = CageFitKind::default().name())]
    pub cage_fit: CageFitKind,
    /// Mesh rows used by CageUp/CageRev (Green: MaxVol rows of [φ ψ], least squares).
    #[arg(long, value_parser = kind_parser::<FitRowsKind>(), default_value = FitRowsKind::default().name())]
    pub fit_rows: FitRowsKind,
    /// Joint localisation of the skeleton updater.
    #[arg(long, value_parser = kind_parser::<LocalisationKind>(), default_value = LocalisationKind::default().name())]
    pub localisation: LocalisationKind,
    /// What CageUp fits with DQS/CoR.
    #[arg(long, value_parser = kind_parser::<CageFitSource>(), default_value = CageFitSource::default().name())]
    pub fit_source: CageFitSource,
    /// Precision of the cage coordinates Φ in the per-frame products M = ΦC.
    #[arg(long, value_parser = kind_parser::<CoordsPrecision>(), default_value = CoordsPrecision::default().name())]
    pub coords_precision: CoordsPrecision,
    /// Keep a cage-weights file's Φ even when it does not reproduce the mesh (M ≠ ΦC, e.g. the
    /// tool's 6 decimals): to compare with the tool. By default such a Φ is recomputed, so that
    /// the first cage edit moves only what it touches.
    #[arg(long)]
    pub keep_file_coords: bool,
    /// Green rigs: when CageUp finds no current cage C' for a pose (past a fold), `refuse` the
    /// event and stop, or `keep` it: the skin and skeletons exact, C' the fit's closest cage
    /// (written with a warning), grabs of C' refused until a pose fits again.
    #[arg(long, value_parser = kind_parser::<UnfittedCagePolicy>(), default_value = "refuse")]
    pub unfitted_cage: UnfittedCagePolicy,
    /// Green rigs: the face term of the map M = φC + ψ·g(C): `fold-safe` (smooth when a
    /// current cage triangle folds) or `lipman` (Lipman et al.'s stretched normal, which jumps
    /// there). See docs/green-coordinates.md.
    #[arg(long, value_parser = kind_parser::<FaceTermKind>(), default_value = FaceTermKind::default().name())]
    pub green_face_term: FaceTermKind,
}

impl SessionArgs {
    pub fn options(&self) -> SessionOptions {
        SessionOptions {
            coords: self.coords,
            localisation: self.localisation.localisation(),
            fit_rows: self.fit_rows.into(),
            fit_source: self.fit_source,
            cage_coords_precision: self.coords_precision,
            given_cage_coords: if self.keep_file_coords {
                GivenCageCoords::Keep
            } else {
                GivenCageCoords::RecomputeIfInexact
            },
            unfitted_cage: self.unfitted_cage,
            cage_fit: self.cage_fit,
            green_face_term: self.green_face_term,
            ..SessionOptions::default()
        }
    }
}

/// Warns on stderr when the current cage C' that `what` shows is not CageUp's fit (kept under
/// `--unfitted-cage keep`).
pub fn warn_if_unfitted(what: &str, session: &RigSession) {
    if let Some(unfitted) = session.posed_cage_unfitted() {
        eprintln!("warning: {what}: {unfitted}; it shows the fit's closest cage");
    }
}

/// `error` in `context` ("sample t = 0.5", a script's path, …), with the option that keeps such
/// events when it is a refused Green event (its cause chain holds [`cagerig::RigError::GreenFitFailed`]).
pub fn event_error(
    context: impl std::fmt::Display,
    error: impl std::error::Error + 'static,
) -> anyhow::Error {
    let first: &(dyn std::error::Error + 'static) = &error;
    let refused_fit = std::iter::successors(Some(first), |e| e.source()).any(|e| {
        matches!(
            e.downcast_ref::<cagerig::RigError>(),
            Some(cagerig::RigError::GreenFitFailed { .. })
        )
    });
    let hint = if refused_fit {
        " (`--unfitted-cage keep` keeps such events: the skin posed exactly, the current cage \
         left unfitted)"
    } else {
        ""
    };
    anyhow::anyhow!("{context}: {error}{hint}")
}

pub fn start_session(
    loaded: LoadedRig,
    options: SessionOptions,
) -> anyhow::Result<(RigSession, Vec<Warning>)> {
    let options = SessionOptions {
        allow_mesh_outside_cage: loaded.allow_outside_cage,
        ..options
    };
    // The session binds with the coordinates it was asked for and reports their progress.
    let bar = crate::rig_source::coords_progress_bar(
        loaded.parts.mesh.num_vertices(),
        true,
        "cage coordinates",
    );
    let report = |_stage: BindStage, done: usize, _total: usize| {
        if let Some(bar) = &bar {
            bar.set_position(done as u64);
        }
    };
    let cage_name = loaded.cage_name();
    let bound = RigSession::with_progress(loaded.parts, options, &report);
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    // The session is where the cage is validated (once); its cage errors name the cage's file.
    let (session, warnings) = bound.map_err(|e| {
        if e.concerns_cage() {
            anyhow::anyhow!("{cage_name}: {e}")
        } else {
            anyhow::Error::new(e).context("assembling the rig")
        }
    })?;
    let mut all = loaded.warnings;
    all.extend(warnings);
    Ok((session, all))
}

/// The skinning method of a run, by the one rule of every command: `--skinning`, else the
/// script's `"skinning"`, else the method the file says its authoring tool uses (FBX skin
/// deformers; said in a note), else LBS.
pub fn choose_skinning(
    option: Option<SkinningMethod>,
    script: Option<SkinningMethod>,
    loaded: &LoadedRig,
) -> SkinningMethod {
    let chosen = option.or(script);
    let method = SkinningMethod::chosen_else_file(chosen, loaded.file_skinning);
    if chosen.is_none() && method != SkinningMethod::default() {
        eprintln!(
            "note: {}: skinning with {}, as the file's skin says (choose another with \
             --skinning)",
            loaded.name,
            method.label()
        );
    }
    method
}

/// Replays every step of the edit script `script`, read from `path`, on `session`: checked
/// against the session first, then run step by step; an error names the file.
pub fn replay_script(
    script: &cagerig::script::EditScript,
    path: &std::path::Path,
    session: &mut RigSession,
) -> anyhow::Result<()> {
    use anyhow::Context;
    script
        .validate(session)
        .with_context(|| format!("in {}", path.display()))?;
    for k in 0..script.steps.len() {
        script
            .run_step(k, session)
            .with_context(|| format!("in {}", path.display()))?;
    }
    Ok(())
}
