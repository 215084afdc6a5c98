//! Undo / redo of whole editable states: each step stores the state before an action (the
//! editable state is small — C, the joints, the pose, the keys, the method — so snapshots are
//! simpler and more exact than inverse operations).

/// One undoable step: a label for the menu and the state to go back to.
#[derive(Debug, Clone)]
struct Step<T> {
    label: String,
    state: T,
}

/// Undo and redo stacks of states `T`, at most `limit` deep.
#[derive(Debug, Clone)]
pub struct History<T> {
    undo: Vec<Step<T>>,
    redo: Vec<Step<T>>,
    limit: usize,
}

impl<T> Default for History<T> {
    fn default() -> Self {
        Self::new(500)
    }
}

impl<T> History<T> {
    /// Empty history keeping the last `limit` steps (at least 1).
    pub fn new(limit: usize) -> Self {
        Self {
            undo: Vec::new(),
            redo: Vec::new(),
            limit: limit.max(1),
        }
    }

    /// Records an action: `before` is the state it started from. Clears the redo stack.
    pub fn record(&mut self, label: impl Into<String>, before: T) {
        self.redo.clear();
        self.undo.push(Step {
            label: label.into(),
            state: before,
        });
        if self.undo.len() > self.limit {
            self.undo.remove(0);
        }
    }

    /// The state to restore for undo, given the state now (kept for redo); `None` when there
    /// is nothing to undo.
    pub fn undo(&mut self, now: T) -> Option<T> {
        let step = self.undo.pop()?;
        self.redo.push(Step {
            label: step.label,
            state: now,
        });
        Some(step.state)
    }

    /// The state to restore for redo, given the state now (kept for undo).
    pub fn redo(&mut self, now: T) -> Option<T> {
        let step = self.redo.pop()?;
        self.undo.push(Step {
            label: step.label,
            state: now,
        });
        Some(step.state)
    }

    /// Puts back a step taken by [`History::undo`] / [`History::redo`] whose restore failed.
    pub fn put_back_undo(&mut self) {
        if let Some(step) = self.redo.pop() {
            self.undo.push(step);
        }
    }

    /// Label of the next undo step.
    pub fn undo_label(&self) -> Option<&str> {
        self.undo.last().map(|s| s.label.as_str())
    }

    /// Label of the next redo step.
    pub fn redo_label(&self) -> Option<&str> {
        self.redo.last().map(|s| s.label.as_str())
    }

    pub fn undo_len(&self) -> usize {
        self.undo.len()
    }

    pub fn redo_len(&self) -> usize {
        self.redo.len()
    }

    pub fn clear(&mut self) {
        self.undo.clear();
        self.redo.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn undo_then_redo_walks_the_states_back_and_forth() {
        let mut h = History::new(10);
        let mut state = 0;
        for next in 1..=3 {
            h.record(format!("set {next}"), state);
            state = next;
        }
        assert_eq!(h.undo_label(), Some("set 3"));
        state = h.undo(state).unwrap();
        assert_eq!(state, 2);
        state = h.undo(state).unwrap();
        assert_eq!(state, 1);
        assert_eq!(h.redo_label(), Some("set 2"));
        state = h.redo(state).unwrap();
        assert_eq!(state, 2);
        state = h.redo(state).unwrap();
        assert_eq!(state, 3);
        assert!(h.redo(state).is_none());
    }

    #[test]
    fn a_new_action_clears_redo() {
        let mut h = History::new(10);
        h.record("a", 0);
        let s = h.undo(1).unwrap();
        assert_eq!(s, 0);
        h.record("b", s);
        assert_eq!(h.redo_len(), 0);
        assert!(h.redo(5).is_none());
    }

    #[test]
    fn the_limit_drops_the_oldest_steps() {
        let mut h = History::new(2);
        for i in 0..5 {
            h.record("x", i);
        }
        assert_eq!(h.undo_len(), 2);
        assert_eq!(h.undo(99), Some(4));
        assert_eq!(h.undo(4), Some(3));
        assert_eq!(h.undo(3), None);
    }

    #[test]
    fn put_back_restores_a_failed_undo() {
        let mut h = History::new(5);
        h.record("a", 1);
        let _ = h.undo(2);
        h.put_back_undo();
        assert_eq!(h.undo_len(), 1);
        assert_eq!(h.redo_len(), 0);
    }
}
