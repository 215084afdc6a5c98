//! How much work one Green CageUp may do: the direct solve's steps and what follows when it
//! stops short ([`FitBudget::FULL`] for every event, [`FitBudget::UNFITTED_STREAK`] while a
//! kept event's C' is unfitted).

use super::MAX_STEPS;

/// What a CageUp does when its direct solve stops above the accepted gradient.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AfterDirectSolve {
    /// Continue in pieces from the last accepted solution (every event's).
    Continuation,
    /// Solve once more, within the same steps, from the last accepted solution (and keep the
    /// direct solve's cage when that fails too): cheap, and enough to find the cage again
    /// when the pose comes back near the last one fitted.
    RetryFromLastSolution,
}

/// How much work one CageUp may do.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FitBudget {
    /// Steps of the direct solve (and of a retry).
    pub steps: usize,
    /// What follows a direct solve that stops above the accepted gradient.
    pub then: AfterDirectSolve,
}

impl FitBudget {
    /// Every event's: [`MAX_STEPS`], then the continuation.
    pub const FULL: Self = Self {
        steps: MAX_STEPS,
        then: AfterDirectSolve::Continuation,
    };
    /// After an event whose CageUp found no cage, kept with C' unfitted
    /// ([`crate::session::UnfittedCagePolicy::KeepEvent`]): [`UNFITTED_STEPS`] steps from the
    /// moved closest cage, then as many from the last accepted solution, so that a run of poses
    /// past the fold costs a few steps each (with the full budget, 0.2–0.3 s a frame on a
    /// 100-vertex cage; with 2 + 2 steps about 17 ms on CesiumMan, which fits the same samples
    /// as 8 + 8 on the measured characters: `docs/green-coordinates.md`).
    pub const UNFITTED_STREAK: Self = Self {
        steps: UNFITTED_STEPS,
        then: AfterDirectSolve::RetryFromLastSolution,
    };
}

/// Direct-solve steps of [`FitBudget::UNFITTED_STREAK`].
pub const UNFITTED_STEPS: usize = 2;
