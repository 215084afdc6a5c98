//! Barycentric coordinates: mean value (Φ), max-entropy (Ψ projection), MaxVol row selection.
