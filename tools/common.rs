//! Helpers shared by the benchmark tools (included with `#[path = "common.rs"] mod common;`).

/// Median of the finite values of `v` (the mean of the two middle values for an even count);
/// NaN when there is none, so an empty or failed series never panics.
pub fn median(mut v: Vec<f64>) -> f64 {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// FNV-1a, 64 bit, as 16 hex digits: a hash that stays the same across Rust versions and
/// platforms (cache keys of the reference solutions).
#[allow(dead_code)]
pub fn fnv1a(text: &str) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in text.bytes() {
        h ^= b as u64;
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    format!("{h:016x}")
}

/// The steady state of `scene`, built and solved as `tread run --mode steady` does (without
/// its outputs). A scene that cannot be built or solved ends the tool: the error on stderr,
/// exit status 1.
#[allow(dead_code)]
pub fn solved_steady(scene: &tread::io::Scene) -> tread::driver::steady::SteadyRolling {
    let mut st = match tread::driver::steady_run::build_steady(scene) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(1);
        }
    };
    let mut report = Default::default();
    if let Err(e) =
        tread::driver::steady_run::solve_steady(scene, &mut st, false, &mut report, &mut ())
    {
        eprintln!("the steady solve failed: {e}");
        std::process::exit(1);
    }
    st
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_even_empty_and_non_finite() {
        assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(vec![4.0, 1.0, 3.0, 2.0]), 2.5);
        assert_eq!(median(vec![f64::NAN, 5.0, f64::INFINITY]), 5.0);
        assert!(median(vec![]).is_nan());
        assert!(median(vec![f64::NAN]).is_nan());
    }

    #[test]
    fn fnv1a_test_vectors() {
        assert_eq!(fnv1a(""), "cbf29ce484222325");
        assert_eq!(fnv1a("a"), "af63dc4c8601ec8c");
    }
}
