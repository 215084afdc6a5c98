//! MaxVol row selection (placeholder, see next commit).
