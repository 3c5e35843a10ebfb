//! Axis ranges and ticks, computed here for every axis so that plotters' own tick search (which
//! loops forever on a subnormal or overflowing range) never runs.
//!
//! Every function takes any `f64` and terminates with a bounded result: a log axis works in
//! whole decades (at most about 633 between the smallest subnormal and `f64::MAX`), a linear
//! axis in at most [`MAX_LINES`] steps.

/// Most labelled ticks on an axis (their labels would overlap beyond it).
pub const MAX_LABELS: usize = 12;
/// Most grid lines on an axis, the labelled ones included.
pub const MAX_LINES: usize = 120;

/// The smallest positive `f64` (a subnormal).
const TINIEST: f64 = 5e-324;

/// A linear axis keeps its width finite: plotters maps a point by dividing by the width.
const LINEAR_LIMIT: f64 = f64::MAX / 4.0;

/// Axis range covering the finite points (positive ones only on a log axis), padded; `lo < hi`,
/// both finite (and positive on a log axis).
pub fn range(values: impl Iterator<Item = f64>, log: bool) -> Result<(f64, f64), String> {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && (!log || *v > 0.0))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if !lo.is_finite() {
        return Err(
            "no point can be drawn (no finite value, or none positive on a log axis)".into(),
        );
    }
    Ok(if log {
        log_range(lo, hi)
    } else {
        linear_range(lo, hi)
    })
}

/// `[lo, hi]` (positive, finite) widened by a factor 1.25 on both sides, or to a factor 2 when
/// the values are (nearly) equal; in decades, so that neither end overflows or reaches 0.
fn log_range(lo: f64, hi: f64) -> (f64, f64) {
    let (mut l0, mut l1) = (lo.log10(), hi.log10());
    if l1 - l0 < 1.0001f64.log10() {
        l0 -= 2f64.log10();
        l1 += 2f64.log10();
    }
    let pad = 1.25f64.log10();
    let lo = 10f64.powf(l0 - pad).clamp(TINIEST, lo);
    let hi = 10f64.powf(l1 + pad).clamp(hi, f64::MAX);
    (lo, hi)
}

/// `[lo, hi]` padded by 5 % of its width (at least a thousandth of its magnitude), within
/// ±[`LINEAR_LIMIT`] (points beyond it fall off the chart).
fn linear_range(lo: f64, hi: f64) -> (f64, f64) {
    let (lo, hi) = (
        lo.clamp(-LINEAR_LIMIT, LINEAR_LIMIT),
        hi.clamp(-LINEAR_LIMIT, LINEAR_LIMIT),
    );
    // Halves: the width of two values near ±f64::MAX overflows.
    let half_width = hi / 2.0 - lo / 2.0;
    let pad = (half_width * 0.1)
        .max(hi.abs().max(lo.abs()) * 1e-3)
        .max(1e-12);
    (
        (lo - pad).max(-2.0 * LINEAR_LIMIT),
        (hi + pad).min(2.0 * LINEAR_LIMIT),
    )
}

/// A tick label with at most three significant digits and no float noise.
pub fn tick(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let mag = v.abs().log10().floor() as i32;
    if !(-3..=5).contains(&mag) {
        return format!("{v:.2e}");
    }
    let decimals = (2 - mag).max(0) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// `m * 10^e`, correctly rounded (0 below the subnormals, infinite past `f64::MAX`): powers
/// of ten by multiplication drift and reach 0 well before the smallest positive value.
fn times_ten_to(m: u32, e: i32) -> f64 {
    format!("{m}e{e}").parse().unwrap_or(f64::NAN)
}

/// The values `m * 10^e` in `[lo, hi]` for every decade `e` from `e0` to `e1` that `keep(e)`
/// and every `m` in `ms`, increasing, without repeats (subnormals round several to one).
fn multiples(
    (lo, hi): (f64, f64),
    (e0, e1): (i32, i32),
    ms: impl Iterator<Item = u32> + Clone,
    keep: impl Fn(i32) -> bool,
) -> Vec<f64> {
    let mut out: Vec<f64> = Vec::new();
    for e in (e0..=e1).filter(|&e| keep(e)) {
        for m in ms.clone() {
            let v = times_ten_to(m, e);
            if v >= lo && v <= hi && out.last().is_none_or(|&last| v > last) {
                out.push(v);
            }
        }
    }
    out
}

/// Tick values of a log axis over `[lo, hi]`: labelled ones and grid-only ones (the labelled
/// ones among them), each increasing and inside the range, at most [`MAX_LABELS`] and
/// [`MAX_LINES`]. Labelled are 1, 2 and 5 times a power of ten; every integer multiple when
/// fewer than four of those fall inside; tenths of a decade when fewer than two integer
/// multiples do; powers of ten (every k-th decade) when the 1-2-5 values are too many.
/// plotters' own log ticks leave a range that does not span a whole decade, or the part below
/// its first power of ten, without labels.
pub fn log_ticks(lo: f64, hi: f64) -> (Vec<f64>, Vec<f64>) {
    if !(lo > 0.0 && lo <= hi && hi.is_finite()) {
        return (Vec::new(), Vec::new());
    }
    // From -324 (the subnormals) to 308: at most 633 decades.
    let e0 = lo.log10().floor() as i32;
    let e1 = hi.log10().floor() as i32;
    let decades = (e1 - e0 + 1) as usize;
    let span = (lo, hi);
    let any = |_| true;
    let every = (decades * 9 <= MAX_LINES).then(|| multiples(span, (e0, e1), 1..=9, any));
    let nice = (decades <= MAX_LABELS / 3 + 1)
        .then(|| multiples(span, (e0, e1), [1, 2, 5].into_iter(), any))
        .filter(|n| n.len() <= MAX_LABELS);
    let labelled = match (&nice, &every) {
        (Some(nice), _) if nice.len() >= 4 => nice.clone(),
        (_, Some(every)) if every.len() >= 2 && every.len() <= MAX_LABELS => every.clone(),
        (_, Some(every)) if every.len() < 2 => tenths(span, (e0, e1)),
        _ => {
            // Every k-th power of ten, k the first of these that keeps them few enough (at
            // most ceil(n / k) multiples of k among n consecutive decades; n <= 633).
            let k = [1, 2, 5, 10, 20, 50, 100]
                .into_iter()
                .find(|k| decades.div_ceil(*k) <= MAX_LABELS)
                .unwrap_or(100) as i32;
            multiples(span, (e0, e1), 1..=1, |e| e.rem_euclid(k) == 0)
        }
    };
    let light = match every {
        Some(every) if every.len() >= 2 => every,
        Some(_) => tenths_every(span, (e0, e1), 1),
        None if decades <= MAX_LINES => multiples(span, (e0, e1), 1..=1, any),
        None => labelled.clone(),
    };
    let mut light = merge(light, &labelled);
    light.truncate(MAX_LINES);
    (labelled, light)
}

/// Tenths of a decade inside a range holding fewer than two integer multiples (so at most
/// about two decades' worth): every tenth, or every second or fifth when those are too many.
fn tenths(span: (f64, f64), decades: (i32, i32)) -> Vec<f64> {
    [1, 2, 5]
        .into_iter()
        .map(|step| tenths_every(span, decades, step))
        .find(|t| t.len() <= MAX_LABELS)
        .unwrap_or_default()
}

/// `m * 10^(e-1)` for `m` in 10..=99 divisible by `step`, inside the range.
fn tenths_every(span: (f64, f64), (e0, e1): (i32, i32), step: u32) -> Vec<f64> {
    multiples(
        span,
        (e0.saturating_sub(1), e1.saturating_sub(1)),
        (10..=99).filter(move |m| m % step == 0),
        |_| true,
    )
}

/// `a` and `b` (each increasing) as one increasing list without repeats.
fn merge(a: Vec<f64>, b: &[f64]) -> Vec<f64> {
    let mut all: Vec<f64> = a.into_iter().chain(b.iter().copied()).collect();
    all.sort_by(f64::total_cmp);
    all.dedup();
    all
}

/// Tick values of a linear axis over `[lo, hi]` (finite): labelled ones at a 1-2-5 step, at most
/// [`MAX_LABELS`], and grid-only ones at a fifth of that step.
pub fn linear_ticks(lo: f64, hi: f64) -> (Vec<f64>, Vec<f64>) {
    if !(lo <= hi && lo.is_finite() && hi.is_finite()) {
        return (Vec::new(), Vec::new());
    }
    // Halves: the width of two values near ±f64::MAX overflows.
    let half_width = hi / 2.0 - lo / 2.0;
    if half_width <= 0.0 {
        return (vec![lo], vec![lo]);
    }
    // The step: the first 1-2-5 multiple of a power of ten that cuts the range into at most
    // eight parts (so at most nine labels).
    let target = half_width / 4.0;
    let decade = 10f64.powi(target.log10().floor() as i32);
    let step = [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * decade)
        .find(|s| *s >= target)
        .unwrap_or(10.0 * decade);
    let labelled = steps(lo, hi, step, MAX_LABELS);
    let light = merge(steps(lo, hi, step / 5.0, MAX_LINES), &labelled);
    (labelled, light)
}

/// Multiples of `step` in `[lo, hi]`, at most `most` (a step too fine for the values' precision
/// repeats values, which are dropped).
fn steps(lo: f64, hi: f64, step: f64, most: usize) -> Vec<f64> {
    if !(step > 0.0 && step.is_finite()) {
        return Vec::new();
    }
    let first = (lo / step).ceil();
    let mut out: Vec<f64> = Vec::new();
    for i in 0..=most {
        let v = (first + i as f64) * step;
        if v.is_nan() || v > hi || out.len() == most {
            break;
        }
        if v >= lo && out.last().is_none_or(|&last| v > last) {
            // `+ 0.0`: -0 (from a negative first multiple times 0) is labelled 0.
            out.push(v + 0.0);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn log_ticks_label_ranges_that_miss_a_power_of_ten() {
        let (bold, light) = log_ticks(0.0165, 0.44);
        let want = [0.02, 0.05, 0.1, 0.2];
        assert_eq!(bold.len(), want.len(), "{bold:?}");
        assert!(bold.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-12));
        assert_eq!(light.len(), 8 + 4, "0.02..0.09 and 0.1..0.4: {light:?}");
        // Less than a decade: every integer multiple is labelled.
        let (bold, _) = log_ticks(0.25, 0.9);
        assert_eq!(bold.len(), 7);
        assert!((bold[0] - 0.3).abs() < 1e-12 && (bold[6] - 0.9).abs() < 1e-12);
    }

    #[test]
    fn a_range_between_two_integer_multiples_gets_tenths() {
        let (bold, light) = log_ticks(1.05, 1.65);
        let want = [1.1, 1.2, 1.3, 1.4, 1.5, 1.6];
        assert_eq!(bold.len(), want.len(), "{bold:?}");
        assert!(bold.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-12));
        assert_eq!(light, bold);
    }

    #[test]
    fn many_decades_are_labelled_at_every_kth_power_of_ten() {
        // 1e-300 to 1e300: 601 decades, labelled every 100th.
        let (bold, light) = log_ticks(1e-300, 1e300);
        let want = [1e-300, 1e-200, 1e-100, 1.0, 1e100, 1e200, 1e300];
        assert_eq!(bold, want);
        assert_eq!(
            light, want,
            "more decades than grid lines: the labelled ones"
        );
        // Ten decades: the powers of ten, with a grid line at every integer multiple.
        let (bold, light) = log_ticks(1e-5, 1e5);
        assert_eq!(bold.len(), 11, "{bold:?}");
        assert_eq!(light.len(), 10 * 9 + 1, "1e-5 .. 9e4 and 1e5: {light:?}");
        // Thirteen: every second power of ten, aligned to 1.
        let (bold, _) = log_ticks(1e-6, 1e6);
        assert_eq!(bold.len(), 7, "{bold:?}");
        assert!(bold.contains(&1.0) && bold.contains(&1e-6), "{bold:?}");
    }

    #[test]
    fn subnormal_and_extreme_ranges_end_with_ticks_inside() {
        for (lo, hi) in [
            (5e-324, 5e-324),
            (5e-324, 1e-320),
            (1e-310, 1e-308),
            (5e-324, f64::MAX),
            (1e308, f64::MAX),
        ] {
            let (bold, light) = log_ticks(lo, hi);
            assert!(bold.iter().chain(&light).all(|v| *v >= lo && *v <= hi));
            assert!(bold.len() <= MAX_LABELS && light.len() <= MAX_LINES);
        }
        // Every value the axis may get, padded: some labels.
        for v in [5e-324, 1e-310, 1e-300, 1.0, 1e300, f64::MAX] {
            let (lo, hi) = range([v, v].into_iter(), true).unwrap();
            assert!(lo > 0.0 && lo < hi && hi.is_finite(), "{v}: {lo} {hi}");
            let (bold, _) = log_ticks(lo, hi);
            assert!(!bold.is_empty(), "{v}: {lo}..{hi}");
        }
    }

    #[test]
    fn linear_ticks_are_few_round_and_inside() {
        let (bold, light) = linear_ticks(-0.05, 1.05);
        let want = [0.0, 0.2, 0.4, 0.6, 0.8, 1.0];
        assert_eq!(bold.len(), want.len(), "{bold:?}");
        assert!(bold.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-12));
        assert!(light.len() > bold.len());
        let (lo, hi) = range([-f64::MAX, f64::MAX].into_iter(), false).unwrap();
        assert!(lo.is_finite() && hi.is_finite() && (hi - lo).is_finite());
        let (bold, _) = linear_ticks(lo, hi);
        assert!(bold.len() >= 2 && bold.len() <= MAX_LABELS, "{bold:?}");
    }

    #[test]
    fn tick_labels_have_no_float_noise() {
        assert_eq!(tick(0.30000000000000004), "0.3");
        assert_eq!(tick(0.1 + 0.2), "0.3");
        assert_eq!(tick(12.5), "12.5");
        assert_eq!(tick(1234.0), "1234");
        assert_eq!(tick(0.000123), "1.23e-4");
        assert_eq!(tick(2.0), "2");
    }

    /// Any finite positive `f64`, from its bits: uniform over the bit patterns, or among the
    /// subnormals, or in the highest binade (each a third of the time; the bit patterns alone
    /// would give a subnormal once in 2048).
    fn positive() -> impl Strategy<Value = f64> {
        prop_oneof![
            1u64..0x7ff0_0000_0000_0000,
            1u64..0x0010_0000_0000_0000,
            0x7fe0_0000_0000_0000u64..0x7ff0_0000_0000_0000,
        ]
        .prop_map(f64::from_bits)
    }

    /// Any finite `f64`, from its bits.
    fn finite() -> impl Strategy<Value = f64> {
        any::<u64>().prop_map(|b| {
            let v = f64::from_bits(b);
            if v.is_finite() { v } else { 0.0 }
        })
    }

    /// Ticks are increasing, inside `[lo, hi]` and within their bounds.
    fn well_formed(lo: f64, hi: f64, (bold, light): &(Vec<f64>, Vec<f64>)) -> Result<(), String> {
        for (what, t, most) in [("labelled", bold, MAX_LABELS), ("grid", light, MAX_LINES)] {
            if t.len() > most {
                return Err(format!("{} {what} ticks", t.len()));
            }
            if !t.iter().all(|v| *v >= lo && *v <= hi) {
                return Err(format!("{what} tick outside {lo}..{hi}: {t:?}"));
            }
            if !t.windows(2).all(|w| w[0] < w[1]) {
                return Err(format!("{what} ticks not increasing: {t:?}"));
            }
        }
        Ok(())
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 2000, .. ProptestConfig::default() })]

        #[test]
        fn log_ticks_end_bounded_and_inside_for_any_positive_range(
            a in positive(), b in positive()
        ) {
            let (lo, hi) = (a.min(b), a.max(b));
            let ticks = log_ticks(lo, hi);
            prop_assert!(well_formed(lo, hi, &ticks).is_ok(), "{:?}", well_formed(lo, hi, &ticks));
        }

        /// The axis a chart of these values gets: a positive, finite range holding them all,
        /// with at least one labelled tick (two where the range is not among the subnormals).
        #[test]
        fn any_positive_values_get_a_labelled_log_axis(
            values in proptest::collection::vec(positive(), 1..6)
        ) {
            let (lo, hi) = range(values.iter().copied(), true).unwrap();
            prop_assert!(lo > 0.0 && lo < hi && hi.is_finite());
            prop_assert!(values.iter().all(|v| *v >= lo && *v <= hi));
            let ticks = log_ticks(lo, hi);
            prop_assert!(well_formed(lo, hi, &ticks).is_ok(), "{:?}", well_formed(lo, hi, &ticks));
            let want = if lo >= f64::MIN_POSITIVE { 2 } else { 1 };
            prop_assert!(ticks.0.len() >= want, "{lo}..{hi}: {:?}", ticks.0);
        }

        #[test]
        fn any_finite_values_get_a_labelled_linear_axis(
            values in proptest::collection::vec(finite(), 1..6)
        ) {
            let (lo, hi) = range(values.iter().copied(), false).unwrap();
            prop_assert!(lo < hi && (hi - lo).is_finite());
            let ticks = linear_ticks(lo, hi);
            prop_assert!(well_formed(lo, hi, &ticks).is_ok(), "{:?}", well_formed(lo, hi, &ticks));
            prop_assert!(ticks.0.len() >= 2, "{lo}..{hi}: {:?}", ticks.0);
        }
    }
}
