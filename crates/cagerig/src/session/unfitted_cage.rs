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

use super::RigSession;
use crate::error::{RigError, UnfittedCage};

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

    /// The accepted names as a sentence: `"refuse or keep"`.
    pub fn names_text() -> String {
        crate::error::names_sentence(&Self::ALL.map(Self::name))
    }
}

crate::named_kind::named_kind!(UnfittedCagePolicy, UnknownUnfittedCagePolicy);

impl RigSession {
    /// Why C' is not CageUp's fit of the current state, when it is not (only under
    /// [`UnfittedCagePolicy::KeepEvent`], after an event whose Green CageUp found no current
    /// cage); `None` while C' is the fit.
    pub fn posed_cage_unfitted(&self) -> Option<UnfittedCage> {
        self.rest_map.unfitted()
    }

    /// The session's [`UnfittedCagePolicy`].
    pub fn unfitted_cage_policy(&self) -> UnfittedCagePolicy {
        self.options.unfitted_cage
    }

    /// Sets the [`UnfittedCagePolicy`] of the next events (an unfitted C' stays so until an
    /// event fits it).
    pub fn set_unfitted_cage_policy(&mut self, policy: UnfittedCagePolicy) {
        self.options.unfitted_cage = policy;
    }

    /// `Err` when C' is unfitted: grabs of it are refused then.
    pub(super) fn check_posed_cage_fitted(&self) -> Result<(), RigError> {
        match self.posed_cage_unfitted() {
            Some(unfitted) => Err(RigError::PosedCageUnfitted(unfitted)),
            None => Ok(()),
        }
    }

    /// Whether an event whose CageUp ended as `failure` is refused under the policy.
    pub(super) fn refuses_unfitted(&self, failure: Option<RigError>) -> Option<RigError> {
        match self.options.unfitted_cage {
            UnfittedCagePolicy::Refuse => failure,
            UnfittedCagePolicy::KeepEvent => None,
        }
    }
}
