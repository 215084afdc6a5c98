//! The Le–Hodgins weight similarity s(w_p, w_v) (Le & Hodgins 2016; the kernel of Eq. 5).

/// Le–Hodgins similarity `s(w_p, w_v)` of two sparse weight rows (ascending joints).
pub fn weight_similarity(
    joints_p: &[u32],
    weights_p: &[f64],
    joints_v: &[u32],
    weights_v: &[f64],
    inv_sigma_sq: f64,
) -> f64 {
    // Common support, at most min(len) entries; rows are short (≤ a few dozen).
    let mut common_p = [0.0f64; 32];
    let mut common_v = [0.0f64; 32];
    let mut n = 0;
    let (mut a, mut b) = (0, 0);
    while a < joints_p.len() && b < joints_v.len() {
        match joints_p[a].cmp(&joints_v[b]) {
            std::cmp::Ordering::Less => a += 1,
            std::cmp::Ordering::Greater => b += 1,
            std::cmp::Ordering::Equal => {
                if n < common_p.len() {
                    common_p[n] = weights_p[a];
                    common_v[n] = weights_v[b];
                    n += 1;
                }
                a += 1;
                b += 1;
            }
        }
    }
    let mut sum = 0.0;
    for j in 0..n {
        for k in j + 1..n {
            let cross = common_p[j] * common_v[k] - common_p[k] * common_v[j];
            sum += common_p[j]
                * common_p[k]
                * common_v[j]
                * common_v[k]
                * (-cross * cross * inv_sigma_sq).exp();
        }
    }
    2.0 * sum
}
