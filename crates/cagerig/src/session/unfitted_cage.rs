//! What an event does when a Green CageUp finds no current cage C' for the state it reaches
//! (where the fitted cage would fold: `docs/green-coordinates.md`, "Where a Green rig stops").
//!
//! - [`UnfittedCagePolicy::Refuse`] (the default): the event is refused with
//!   [`RigError::GreenFitFailed`] and every structure stays as it was.
//! - [`UnfittedCagePolicy::KeepEvent`]: the event is kept. The pose, the rest cage C, the
//!   skeletons S and S' and the skins M and M' are exact — skinning and SkelUp never read C' —
//!   and C' holds the fit's closest cage, reported by [`RigSession::posed_cage_unfitted`]. A
//!   grab of C' is then refused ([`RigError::PosedCageUnfitted`]: CageRev inverts CageUp at a
//!   fitted C'), while rest-cage edits, poses and animation go on; the next event whose CageUp
//!   converges makes C' its fit again. So a Green rig whose cage cannot follow a character's
//!   poses still gives its shape-preserving rest-cage edits on the posed skin.
//!
//! Mean value rigs always fit C' (CageUp is linear); the policy only matters for Green rigs.

/// What an event does when a Green CageUp finds no current cage for it (module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub enum UnfittedCagePolicy {
    /// Refuse the event; the rig stays as it was.
    #[default]
    Refuse,
    /// Keep the event with C' unfitted (the skin and skeletons exact, grabs of C' refused).
    KeepEvent,
}

/// A policy name that [`UnfittedCagePolicy::from_str`] does not know.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "unknown unfitted-cage policy {found:?}: expected {}",
    UnfittedCagePolicy::names_text()
)]
pub struct UnknownUnfittedCagePolicy {
    /// The name as given.
    pub found: String,
}

impl UnfittedCagePolicy {
    /// Every policy, in the order front ends list them.
    pub const ALL: [UnfittedCagePolicy; 2] = [Self::Refuse, Self::KeepEvent];

    /// The name in options and files: `"refuse"` or `"keep"`.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Refuse => "refuse",
            Self::KeepEvent => "keep",
        }
    }
}

crate::named_kind::named_kind!(UnfittedCagePolicy, UnknownUnfittedCagePolicy);
