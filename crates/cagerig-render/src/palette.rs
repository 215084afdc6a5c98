//! Colour maps for per-vertex scalars: a sequential map for weights in [0, 1] and a diverging
//! map, symmetric about zero, for quantities that go negative (mean value coordinates).
//!
//! Both are piecewise-linear in sRGB through control points taken from perceptually ordered
//! published maps (sequential: the viridis family's end points and mid tones; diverging: a
//! blue–white–red map in the style of ColorBrewer's RdBu), so they read on paper and for
//! colour-blind viewers. Colours are `[r, g, b]` in sRGB, each in `[0, 1]`.

/// Which palette a scalar field uses.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ColorMap {
    /// `value` in `[lo, hi]` → dark blue … yellow (values outside are clamped).
    Sequential {
        /// Value mapped to the first colour.
        lo: f64,
        /// Value mapped to the last colour.
        hi: f64,
    },
    /// `value` in `[−limit, limit]` → blue … white (0) … red (clamped outside).
    Diverging {
        /// Magnitude mapped to the end colours (0 is white).
        limit: f64,
    },
}

const SEQUENTIAL: [[f64; 3]; 6] = [
    [0.267, 0.005, 0.329],
    [0.255, 0.267, 0.529],
    [0.164, 0.471, 0.558],
    [0.134, 0.659, 0.518],
    [0.478, 0.821, 0.319],
    [0.993, 0.906, 0.144],
];

const DIVERGING: [[f64; 3]; 7] = [
    [0.020, 0.188, 0.380],
    [0.129, 0.400, 0.675],
    [0.573, 0.773, 0.871],
    [0.969, 0.969, 0.969],
    [0.957, 0.647, 0.510],
    [0.698, 0.094, 0.169],
    [0.404, 0.000, 0.122],
];

fn interpolate(stops: &[[f64; 3]], t: f64) -> [f64; 3] {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = t * (stops.len() - 1) as f64;
    let i = (x.floor() as usize).min(stops.len() - 2);
    let f = x - i as f64;
    let (a, b) = (stops[i], stops[i + 1]);
    [
        a[0] + f * (b[0] - a[0]),
        a[1] + f * (b[1] - a[1]),
        a[2] + f * (b[2] - a[2]),
    ]
}

impl ColorMap {
    /// Sequential map over the range of `values` (or `[0, 1]` when it is empty or flat).
    pub fn sequential_for(values: &[f64]) -> Self {
        let (lo, hi) = finite_range(values);
        if hi > lo {
            ColorMap::Sequential { lo, hi }
        } else {
            ColorMap::Sequential { lo: 0.0, hi: 1.0 }
        }
    }

    /// Diverging map symmetric about zero covering the largest magnitude in `values`.
    pub fn diverging_for(values: &[f64]) -> Self {
        let (lo, hi) = finite_range(values);
        let limit = lo.abs().max(hi.abs());
        ColorMap::Diverging {
            limit: if limit > 0.0 { limit } else { 1.0 },
        }
    }

    /// Diverging map symmetric about zero scaled to the bulk of `values`: its limit is the
    /// `quantile` (in (0, 1]) of their magnitudes, so that a few large values (Φ near its own
    /// cage vertex) do not leave the rest white; larger values saturate at the ends.
    pub fn diverging_robust(values: &[f64], quantile: f64) -> Self {
        let mut magnitudes: Vec<f64> = values
            .iter()
            .filter(|v| v.is_finite())
            .map(|v| v.abs())
            .collect();
        if magnitudes.is_empty() {
            return ColorMap::Diverging { limit: 1.0 };
        }
        let k = ((magnitudes.len() - 1) as f64 * quantile.clamp(0.0, 1.0)).round() as usize;
        let (_, &mut limit, _) = magnitudes.select_nth_unstable_by(k, f64::total_cmp);
        ColorMap::Diverging {
            limit: if limit > 0.0 { limit } else { 1.0 },
        }
    }

    /// The sRGB colour of `value`. Non-finite values map to the palette's low end.
    pub fn color(&self, value: f64) -> [f64; 3] {
        match *self {
            ColorMap::Sequential { lo, hi } => interpolate(&SEQUENTIAL, (value - lo) / (hi - lo)),
            ColorMap::Diverging { limit } => interpolate(&DIVERGING, 0.5 + 0.5 * value / limit),
        }
    }

    /// [`color`](Self::color) as 8-bit sRGB with opaque alpha.
    pub fn color_u8(&self, value: f64) -> [u8; 4] {
        let [r, g, b] = self.color(value);
        [to_u8(r), to_u8(g), to_u8(b), 255]
    }
}

/// Rounds a `[0, 1]` channel to 8 bits.
pub fn to_u8(c: f64) -> u8 {
    (c.clamp(0.0, 1.0) * 255.0).round() as u8
}

fn finite_range(values: &[f64]) -> (f64, f64) {
    values
        .iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_robust_diverging_map_follows_the_bulk_of_the_values() {
        let mut values = vec![0.01; 99];
        values.push(0.9);
        let ColorMap::Diverging { limit } = ColorMap::diverging_robust(&values, 0.98) else {
            panic!("diverging")
        };
        assert_eq!(limit, 0.01);
        assert_eq!(
            ColorMap::diverging_for(&values),
            ColorMap::Diverging { limit: 0.9 }
        );
        assert_eq!(
            ColorMap::diverging_robust(&[], 0.98),
            ColorMap::Diverging { limit: 1.0 }
        );
    }

    fn luminance(c: [f64; 3]) -> f64 {
        0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
    }

    #[test]
    fn sequential_is_monotone_in_luminance_and_hits_its_ends() {
        let map = ColorMap::Sequential { lo: 0.0, hi: 1.0 };
        assert_eq!(map.color(0.0), SEQUENTIAL[0]);
        assert_eq!(map.color(1.0), SEQUENTIAL[5]);
        assert_eq!(map.color(-3.0), SEQUENTIAL[0]);
        assert_eq!(map.color(7.0), SEQUENTIAL[5]);
        let mut last = -1.0;
        for i in 0..=100 {
            let l = luminance(map.color(i as f64 / 100.0));
            assert!(l > last, "luminance not increasing at {i}");
            last = l;
        }
    }

    #[test]
    fn diverging_is_white_at_zero_and_symmetric_in_lightness() {
        let map = ColorMap::diverging_for(&[-0.2, 0.5, 0.1]);
        assert_eq!(map, ColorMap::Diverging { limit: 0.5 });
        assert_eq!(map.color(0.0), DIVERGING[3]);
        let neg = map.color(-0.5);
        let pos = map.color(0.5);
        assert!(neg[2] > neg[0], "negative end is blue");
        assert!(pos[0] > pos[2], "positive end is red");
        for t in [0.1, 0.25, 0.4] {
            let (a, b) = (luminance(map.color(-t)), luminance(map.color(t)));
            assert!(
                (a - b).abs() < 0.12,
                "lightness asymmetric at ±{t}: {a} {b}"
            );
            assert!(a < luminance(map.color(0.0)));
        }
    }

    #[test]
    fn ranges_ignore_non_finite_values_and_degenerate_inputs() {
        assert_eq!(
            ColorMap::sequential_for(&[f64::NAN, 2.0, 4.0, f64::INFINITY]),
            ColorMap::Sequential { lo: 2.0, hi: 4.0 }
        );
        assert_eq!(
            ColorMap::sequential_for(&[]),
            ColorMap::Sequential { lo: 0.0, hi: 1.0 }
        );
        assert_eq!(
            ColorMap::diverging_for(&[0.0]),
            ColorMap::Diverging { limit: 1.0 }
        );
        assert_eq!(
            ColorMap::Sequential { lo: 0.0, hi: 1.0 }.color_u8(f64::NAN),
            [68, 1, 84, 255]
        );
    }
}
