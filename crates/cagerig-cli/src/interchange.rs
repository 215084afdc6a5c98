//! Characters from interchange files (`.glb`, `.gltf`, `.fbx`) through `cagerig-formats`: the
//! rig loader's hook, `info` for such files, and the `--animation` track of `animate`.

use std::path::Path;

use anyhow::{Context, bail};
use cagerig::animation::{CageTrack, SkeletonTrack};
use cagerig::cage_source::{CageOrigin, CageRequest, CageSourceError};
use cagerig::playback::{AnimationPlayer, PoseChannels};
use cagerig::session::RigSession;
use cagerig_formats::{
    ImportOptions, ImportedCharacter, MorphTargets, OpenCharacterError, import_character,
};
use serde::Serialize;

use crate::rig_source::FileUse;
use crate::rig_source::LoadedRig;

/// Whether `path` is read by `cagerig-formats` rather than as the paper tool's OBJ file set: the
/// one place the CLI decides how a mesh file is read. By its extension (any case), checked
/// against its first bytes: a file whose content is another format than its extension says, or
/// whose extension is not one cagerig reads, is refused with what it is, instead of being
/// misread as OBJ text.
pub fn is_interchange(path: &Path) -> anyhow::Result<bool> {
    use cagerig_formats::CharacterFormat;
    let content = Content::sniff(path);
    if let Some(format) = CharacterFormat::of(path) {
        if format != CharacterFormat::Gltf && content == Some(Content::GlbMagic) {
            bail!(
                "{}: the file is a binary glTF (it starts with `glTF`), not {}: rename it .glb",
                path.display(),
                format.name()
            );
        }
        return Ok(true);
    }
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    let is_obj = extension.as_deref() == Some("obj");
    if let (true, Some(content)) = (is_obj, content.and_then(Content::character_format)) {
        bail!(
            "{}: the file is {}, not OBJ text: rename it {}",
            path.display(),
            content.0,
            content.1
        );
    }
    if is_obj {
        return Ok(false);
    }
    let mut read = vec!["OBJ (.obj)".to_string()];
    read.extend(CharacterFormat::ALL.iter().map(|f| {
        let extensions: Vec<String> = f.extensions().iter().map(|e| format!(".{e}")).collect();
        format!("{} ({})", f.name(), extensions.join(", "))
    }));
    let hint = match content.and_then(Content::character_format) {
        Some((what, rename)) => format!(" (the file is {what}: rename it {rename})"),
        None => String::new(),
    };
    bail!(
        "{}: expected a mesh in a format cagerig reads, {}; found {}{hint}",
        path.display(),
        read.join(", "),
        match extension {
            Some(e) => format!("the extension .{e}"),
            None => "no extension".to_string(),
        }
    )
}

/// What the first bytes of a file say it is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Content {
    /// `glTF`: a binary glTF (GLB).
    GlbMagic,
    /// `{` (after blanks): JSON, a `.gltf`.
    Json,
    /// `Kaydara FBX Binary`.
    FbxBinary,
    /// Anything else (OBJ text, …).
    Other,
}

impl Content {
    /// The start of the file at `path`; `None` when it cannot be read (its reader says why).
    fn sniff(path: &Path) -> Option<Self> {
        use std::io::Read;
        let mut start = Vec::with_capacity(64);
        std::fs::File::open(path)
            .ok()?
            .take(64)
            .read_to_end(&mut start)
            .ok()?;
        let text = start.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(&start);
        Some(if start.starts_with(b"glTF") {
            Self::GlbMagic
        } else if start.starts_with(b"Kaydara FBX Binary") {
            Self::FbxBinary
        } else if text.iter().find(|b| !b.is_ascii_whitespace()) == Some(&b'{') {
            Self::Json
        } else {
            Self::Other
        })
    }

    /// What the file is and the extension it should have, for a character format.
    fn character_format(self) -> Option<(&'static str, &'static str)> {
        match self {
            Self::GlbMagic => Some(("a binary glTF (it starts with `glTF`)", ".glb")),
            Self::Json => Some(("JSON, as a glTF is (it starts with `{`)", ".gltf")),
            Self::FbxBinary => Some(("a binary FBX (it starts with `Kaydara FBX Binary`)", ".fbx")),
            Self::Other => None,
        }
    }
}

/// Imports a character (its first skin unless `skin` names one).
pub fn import(path: &Path, skin: Option<&str>) -> anyhow::Result<ImportedCharacter> {
    let options = ImportOptions {
        skin: skin.map(str::to_owned),
        ..ImportOptions::default()
    };
    Ok(import_character(path, &options)?)
}

/// Loads a character and its cage (`--cage` OBJ, else a cage node inside the file).
pub fn load_interchange(
    path: &Path,
    cage: Option<&Path>,
    skin: Option<&str>,
    auto_cage: Option<cagerig::cage_gen::CageOptions>,
) -> anyhow::Result<LoadedRig> {
    let options = ImportOptions {
        skin: skin.map(str::to_owned),
        ..ImportOptions::default()
    };
    let request = CageRequest {
        given: cage,
        generate: auto_cage,
        generated: None,
    };
    let opened = match cagerig_formats::open_character(path, &options, &request) {
        Ok(opened) => opened,
        Err(OpenCharacterError::Import(e)) => return Err(e.into()),
        Err(OpenCharacterError::Cage(CageSourceError::Read(e))) => {
            return Err(anyhow::Error::new(e).context(format!(
                "reading the cage {}",
                cage.map(Path::display)
                    .map(|d| d.to_string())
                    .unwrap_or_default()
            )));
        }
        Err(OpenCharacterError::Cage(CageSourceError::Missing { .. })) => bail!(
            "{}: no cage: give --cage CAGE.obj (in the character's space: the file's world space, \
             FBX converted to +Y up metres as `cagerig info` states), add a mesh node \
             named `<name>_cage` (or with extras.cagerig_cage) to the file, or pass \
             --auto-cage to generate one",
            path.display()
        ),
        Err(OpenCharacterError::Cage(
            e @ (CageSourceError::Generate { .. } | CageSourceError::Unusable { .. }),
        )) => {
            return Err(e.into());
        }
    };
    let mut files = vec![FileUse {
        role: "character".into(),
        path: path.to_path_buf(),
    }];
    if let Some(c) = cage {
        files.push(FileUse {
            role: "cage".into(),
            path: c.to_path_buf(),
        });
    }
    let generated_cage = match opened.cage_origin {
        CageOrigin::Generated(g) => Some(*g),
        CageOrigin::Given(_) | CageOrigin::Found => None,
    };
    Ok(LoadedRig {
        name: path.display().to_string(),
        parts: opened.parts,
        files,
        warnings: opened.warnings,
        maxvol_path: None,
        animations: opened.animations,
        morph_targets: opened.morph_targets,
        allow_outside_cage: false,
        generated_cage,
        file_skinning: opened.skinning,
        import_summary: Some(opened.summary),
    })
}

/// Every track an animation command (`animate`, `render`, `export`) plays, before the session
/// exists: see [`AnimationTracks::resolve`].
pub struct AnimationTracks {
    skeleton: Option<SkeletonTrack>,
    channels: PoseChannels,
    cage: Option<CageTrack>,
    /// The chosen imported animation's morph weights (`#keys × #targets`) with the file's
    /// targets and default weights: a cage track once the session can solve for it.
    morph: Option<(Vec<f64>, MorphTargets)>,
    /// Each track as people name it (`animation 'Walk'`, `the skeleton animation FILE`) and its
    /// last key time.
    ends: Vec<(String, f64)>,
    /// The name of what is played: the imported animation's, else its file's stem.
    name: Option<String>,
}

/// The tracks of [`AnimationTracks`] for a session.
pub struct ResolvedTracks {
    pub skeleton: Option<SkeletonTrack>,
    pub channels: PoseChannels,
    pub cage: Option<CageTrack>,
    /// SkelUp held during playback: the skeleton keys already carry the rest joints' motion
    /// (a cagerig export with a cage track, see [`cagerig_formats::morph_cage_track`]).
    pub hold_rest_skeleton: bool,
    /// The name of what is played: the imported animation's, else its file's stem.
    pub name: Option<String>,
}

impl ResolvedTracks {
    /// The player of these tracks on `session` (SkelUp held when the tracks ask for it).
    pub fn player(self, session: &RigSession) -> anyhow::Result<AnimationPlayer> {
        Ok(
            AnimationPlayer::with_channels(session, self.skeleton, self.cage, self.channels)?
                .holding_rest_skeleton(self.hold_rest_skeleton),
        )
    }
}

impl AnimationTracks {
    /// Warns on stderr, once per track, when sample times lie past its last key: a sample there
    /// shows the track's last frame.
    pub fn warn_times_past_end(&self, times: &[f64]) {
        for (label, end) in &self.ends {
            let past: Vec<String> = times
                .iter()
                .filter(|&&t| t > *end)
                .map(|t| t.to_string())
                .collect();
            if past.is_empty() {
                continue;
            }
            eprintln!(
                "warning: --times {} {} past the end of {label} ({end:.3} s): the last frame is \
                 shown",
                past.join(","),
                if past.len() == 1 { "is" } else { "are" },
            );
        }
    }

    /// The cage track of the morph weights, if any, solved on `session`'s rig (with a warning
    /// when the cage does not reproduce the targets to 1e-5 of the diagonal).
    pub fn resolve(self, session: &RigSession) -> anyhow::Result<ResolvedTracks> {
        let Some((weights, morphs)) = self.morph else {
            return Ok(ResolvedTracks {
                skeleton: self.skeleton,
                channels: self.channels,
                cage: self.cage,
                hold_rest_skeleton: false,
                name: self.name,
            });
        };
        let Some(skeleton) = &self.skeleton else {
            bail!("the animation's morph weights need its skeleton track");
        };
        let fit = cagerig_formats::morph_cage_track(session, &morphs, skeleton, &weights)
            .context("playing the animation's morph weights as a cage track")?;
        if let Some(w) = fit.warning() {
            eprintln!("warning: {w}");
        }
        eprintln!(
            "note: the animation's {} morph targets are played as a cage track ({} keys); the joint keys already contain the rest joints' motion, so SkelUp is held during playback",
            morphs.displacements.len(),
            fit.track.num_keyframes()
        );
        Ok(ResolvedTracks {
            skeleton: self.skeleton,
            channels: self.channels,
            cage: Some(fit.track),
            hold_rest_skeleton: true,
            name: self.name,
        })
    }
}

/// Every track an animation command plays: the skeleton track of [`skeleton_track`] with its
/// channels, and the cage track of `--cage-anim` (rest-cage offsets for the rig's cage) or of the
/// imported animation's morph weights (taken from `loaded`).
pub fn animation_tracks(
    loaded: &mut LoadedRig,
    skeleton_anim: Option<&Path>,
    animation: Option<&str>,
    cage_anim: Option<&Path>,
) -> anyhow::Result<AnimationTracks> {
    let (skeleton, channels, morph_weights, skeleton_name) =
        skeleton_track(loaded, skeleton_anim, animation)?;
    let stem = |p: &Path| {
        p.file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .filter(|s| !s.is_empty())
    };
    let mut ends = Vec::new();
    if let Some(track) = &skeleton {
        let label = match (skeleton_anim, &skeleton_name) {
            (Some(p), _) => format!("the skeleton animation {}", p.display()),
            (None, Some(name)) => format!("animation '{name}'"),
            (None, None) => "the animation".to_string(),
        };
        ends.push((label, track.times().last().copied().unwrap_or(0.0)));
    }
    let name = skeleton_name
        .filter(|n| !n.is_empty())
        .or_else(|| cage_anim.and_then(stem));
    let cage = match cage_anim {
        Some(p) => Some(cagerig::io::cage_animation::read_cage_animation(
            p,
            loaded.parts.cage.num_vertices(),
        )?),
        None => None,
    };
    let morph = match morph_weights {
        Some(_) if cage.is_some() => bail!(
            "the animation animates morph weights (played as a cage track); give no --cage-anim with it"
        ),
        Some(weights) => Some((weights, std::mem::take(&mut loaded.morph_targets))),
        None => None,
    };
    if let (Some(track), Some(p)) = (&cage, cage_anim) {
        ends.push((
            format!("the cage animation {}", p.display()),
            track.times().last().copied().unwrap_or(0.0),
        ));
    }
    Ok(AnimationTracks {
        skeleton,
        channels,
        cage,
        morph,
        ends,
        name,
    })
}

/// The track and its name.
type NamedSkeletonTrack = (
    Option<SkeletonTrack>,
    PoseChannels,
    Option<Vec<f64>>,
    Option<String>,
);

/// The skeleton track `animate` plays: `--animation NAME|INDEX` from the imported file (all
/// channels, and its morph weights when it has some), or `--skeleton-anim` in the paper tool's
/// format (rotations and root motion); with its name (the imported animation's, else the
/// file's stem).
pub fn skeleton_track(
    loaded: &LoadedRig,
    skeleton_anim: Option<&Path>,
    animation: Option<&str>,
) -> anyhow::Result<NamedSkeletonTrack> {
    match (animation, skeleton_anim) {
        (Some(_), Some(_)) => bail!("give --animation or --skeleton-anim, not both"),
        (Some(sel), None) => {
            let found = loaded
                .animations
                .iter()
                .find(|a| a.name == sel)
                .or_else(|| {
                    sel.parse::<usize>()
                        .ok()
                        .and_then(|i| loaded.animations.get(i))
                });
            match found {
                Some(a) => Ok((
                    Some(a.track.clone()),
                    PoseChannels::Full,
                    a.morph_weights.clone(),
                    Some(a.name.clone()),
                )),
                None => {
                    let names: Vec<String> = loaded
                        .animations
                        .iter()
                        .enumerate()
                        .map(|(i, a)| format!("{i} {:?}", a.name))
                        .collect();
                    bail!(
                        "{}: no animation named or numbered {sel:?}; it has: {}",
                        loaded.name,
                        if names.is_empty() {
                            "none".into()
                        } else {
                            names.join(", ")
                        }
                    )
                }
            }
        }
        (None, Some(p)) => Ok((
            Some(
                cagerig::io::skeleton_animation::read_skeleton_animation(
                    p,
                    &loaded.parts.skeleton,
                )?
                .0,
            ),
            PoseChannels::RotationsAndRootMotion,
            None,
            p.file_stem().map(|s| s.to_string_lossy().into_owned()),
        )),
        (None, None) => Ok((None, PoseChannels::RotationsAndRootMotion, None, None)),
    }
}

#[derive(Serialize)]
struct InterchangeInfo<'a, R: Serialize> {
    file: String,
    #[serde(flatten)]
    summary: &'a cagerig_formats::ImportSummary,
    /// The importer's warnings; absent when a rig is reported, whose own warnings hold them.
    #[serde(skip_serializing_if = "Option::is_none")]
    warnings: Option<Vec<String>>,
    /// The rig built from the file with a given or generated cage, when `info` binds one.
    #[serde(skip_serializing_if = "Option::is_none")]
    rig: Option<&'a R>,
}

/// The rig `info` builds from a glTF/FBX file: its report and the cage it takes, worded.
pub struct BoundRig<'a, R: Serialize> {
    pub report: &'a R,
    pub cage: String,
}

/// `cagerig info FILE.glb|.gltf|.fbx [--json]`: counts, skins, animations, influences and the
/// importer's warnings.
pub fn info(path: &Path, skin: Option<&str>, json: bool) -> anyhow::Result<()> {
    let c = import(path, skin)?;
    let warnings = c.warnings.iter().map(|w| w.to_string()).collect();
    print_info::<()>(path, &c.summary, Some(warnings), None, json)
}

/// [`info`] of a file already imported (`summary`), with the rig built from it and the cage it
/// names (a `--cage` file, or a generated one): the JSON carries the rig's report as `rig`,
/// whose warnings include the importer's; the text leaves the rig's report to the caller to
/// print after this.
pub fn info_with_rig<R: Serialize>(
    path: &Path,
    summary: &cagerig_formats::ImportSummary,
    rig: BoundRig<'_, R>,
    json: bool,
) -> anyhow::Result<()> {
    print_info(path, summary, None, Some(rig), json)
}

/// The file's facts of [`info`] and [`info_with_rig`].
fn print_info<R: Serialize>(
    path: &Path,
    s: &cagerig_formats::ImportSummary,
    warnings: Option<Vec<String>>,
    rig: Option<BoundRig<'_, R>>,
    json: bool,
) -> anyhow::Result<()> {
    let (rig, cage_used) = rig.map_or((None, None), |r| (Some(r.report), Some(r.cage)));
    let report = InterchangeInfo {
        file: path.display().to_string(),
        summary: s,
        warnings,
        rig,
    };
    if json {
        println!("{}", serde_json::to_string_pretty(&report)?);
        return Ok(());
    }
    println!("file           {} ({})", report.file, s.format);
    println!("space          {}", s.space.describe());
    println!(
        "mesh           {} vertices, {} triangles, {} primitives",
        s.vertices,
        s.triangles,
        s.primitives.len()
    );
    for p in &s.primitives {
        println!(
            "primitive      {}: vertices {}..{}, {} triangles{}",
            p.source,
            p.first_vertex,
            p.first_vertex + p.vertices,
            p.triangles,
            if p.indexed { "" } else { " (no index buffer)" }
        );
    }
    for k in &s.skins {
        println!(
            "skin           {} {:?}: {} joints{}",
            k.index,
            k.name.as_deref().unwrap_or(""),
            k.joints,
            if k.index == s.chosen_skin {
                " (imported)"
            } else {
                ""
            }
        );
    }
    println!("skeleton       {} joints", s.joints);
    println!(
        "{}",
        influences_line(s.max_influences, &s.influences_histogram)
    );
    println!("renormalised   {} weight rows", s.renormalised_rows);
    for a in &s.animations {
        println!(
            "animation      {} {:?}: {:.3} s, {} keys{}{}",
            a.index,
            a.name,
            a.duration,
            a.keys,
            if a.exact { "" } else { " (resampled)" },
            if a.morph_weights {
                ", morph weights (played as a cage track)"
            } else {
                ""
            }
        );
    }
    if s.animations.is_empty() {
        println!("animation      none");
    }
    match (s.cage_in_file, &cage_used) {
        (true, _) => println!("cage in file   yes"),
        (false, None) => {
            println!("cage in file   no (give --cage, or --auto-cage to generate one)")
        }
        (false, Some(cage)) => println!("cage in file   no; the rig below takes {cage}"),
    }
    if let Some(warnings) = &report.warnings {
        if warnings.is_empty() {
            println!("warnings       none");
        }
        for w in warnings {
            println!("warning        {w}");
        }
    }
    Ok(())
}

/// The `influences` line of `info` and `weights`: the most influences of a vertex, and how many
/// vertices have each count (`histogram[k]` vertices have k influences; zero counts left out).
pub fn influences_line(max_influences: usize, histogram: &[usize]) -> String {
    let counts: Vec<String> = histogram
        .iter()
        .enumerate()
        .filter(|(_, n)| **n > 0)
        .map(|(k, n)| format!("{k}: {n}"))
        .collect();
    format!(
        "influences     max {max_influences} per vertex; vertices by count {{{}}}",
        counts.join(", ")
    )
}
