//! Interval evaluation of a compiled [`Function`]: for boxes of its arguments, an interval that
//! holds every value the function takes there. The isosurface's root finder drops the stretches
//! of a ray whose interval excludes the threshold, which is what lets it never skip a thin
//! feature (unlike a step bounded by a guessed gradient).
//!
//! Each operation maps intervals to an interval holding its exact image, widened by a few ulps
//! for rounding. Where an operation may give NaN (a square root of a negative number, a
//! division by an interval holding 0), the result is the whole line: nothing is known there.
//! Comparisons and logic give [0, 1] unless they are decided on the whole box; `select` takes
//! the branches its condition can reach; a pattern's value lies in [0, 1].

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use super::Function;
use super::function::{Binary, Op, SMALL, Unary};

/// No slot: a stack entry computed, not loaded (see `Function::run_interval`).
pub(super) const NO_SLOT: u32 = u32::MAX;

/// A closed interval `[lo, hi]` (`lo <= hi`); the whole line stands for "unknown".
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interval {
    pub lo: f64,
    pub hi: f64,
}

impl Interval {
    pub const ENTIRE: Interval = Interval {
        lo: f64::NEG_INFINITY,
        hi: f64::INFINITY,
    };
    const UNIT: Interval = Interval { lo: 0.0, hi: 1.0 };

    pub fn new(a: f64, b: f64) -> Interval {
        out(a.min(b), a.max(b))
    }

    pub fn point(x: f64) -> Interval {
        if x.is_nan() {
            Interval::ENTIRE
        } else {
            Interval { lo: x, hi: x }
        }
    }

    pub fn contains(&self, x: f64) -> bool {
        self.lo <= x && x <= self.hi
    }

    pub(super) fn hull(self, o: Interval) -> Interval {
        Interval {
            lo: self.lo.min(o.lo),
            hi: self.hi.max(o.hi),
        }
    }

    pub(super) fn is_point(&self) -> bool {
        self.lo == self.hi
    }
}

/// `[lo, hi]` widened outward by a few ulps; the whole line if either end is NaN.
#[inline]
pub(super) fn out(lo: f64, hi: f64) -> Interval {
    if lo.is_nan() || hi.is_nan() {
        return Interval::ENTIRE;
    }
    let pad = |x: f64| 4.0 * f64::EPSILON * x.abs() + f64::MIN_POSITIVE;
    Interval {
        lo: lo - pad(lo),
        hi: hi + pad(hi),
    }
}

/// The image of an increasing function.
#[inline]
fn up(x: Interval, f: impl Fn(f64) -> f64) -> Interval {
    out(f(x.lo), f(x.hi))
}

/// The hull of some values (NaN among them: the whole line).
fn span(vals: &[f64]) -> Interval {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for &v in vals {
        if v.is_nan() {
            return Interval::ENTIRE;
        }
        lo = lo.min(v);
        hi = hi.max(v);
    }
    out(lo, hi)
}

fn truth(definitely: bool, never: bool) -> Interval {
    if definitely {
        Interval::point(1.0)
    } else if never {
        Interval::point(0.0)
    } else {
        Interval::UNIT
    }
}

/// Whether `[lo, hi]` holds `c + k * period` for some whole `k`.
fn holds_phase(x: Interval, c: f64, period: f64) -> bool {
    let k = ((x.lo - c) / period).ceil();
    c + k * period <= x.hi + 1e-12 * (1.0 + x.hi.abs())
        || c + (k - 1.0) * period >= x.lo - 1e-12 * (1.0 + x.lo.abs())
}

pub(super) fn sin(x: Interval) -> Interval {
    if !(x.lo.is_finite() && x.hi.is_finite()) || x.hi - x.lo >= TAU {
        return Interval { lo: -1.0, hi: 1.0 };
    }
    let (a, b) = (x.lo.sin(), x.hi.sin());
    let hi = if holds_phase(x, FRAC_PI_2, TAU) {
        1.0
    } else {
        a.max(b)
    };
    let lo = if holds_phase(x, -FRAC_PI_2, TAU) {
        -1.0
    } else {
        a.min(b)
    };
    let r = out(lo, hi);
    Interval {
        lo: r.lo.max(-1.0),
        hi: r.hi.min(1.0),
    }
}

pub(super) fn mul(x: Interval, y: Interval) -> Interval {
    span(&[x.lo * y.lo, x.lo * y.hi, x.hi * y.lo, x.hi * y.hi])
}

pub(super) fn div(x: Interval, y: Interval) -> Interval {
    if y.is_point() && y.lo == 0.0 && !x.contains(0.0) {
        // A division by exactly 0: an infinity of the numerator's sign.
        return Interval::point(if x.lo > 0.0 {
            f64::INFINITY
        } else {
            f64::NEG_INFINITY
        });
    }
    if y.contains(0.0) {
        return Interval::ENTIRE;
    }
    span(&[x.lo / y.lo, x.lo / y.hi, x.hi / y.lo, x.hi / y.hi])
}

pub(super) fn abs(x: Interval) -> Interval {
    if x.lo >= 0.0 {
        x
    } else if x.hi <= 0.0 {
        Interval {
            lo: -x.hi,
            hi: -x.lo,
        }
    } else {
        Interval {
            lo: 0.0,
            hi: (-x.lo).max(x.hi),
        }
    }
}

/// `x^n` for a whole `n`.
pub(super) fn powi(x: Interval, n: f64) -> Interval {
    if n == 0.0 {
        return Interval::point(1.0);
    }
    let m = n.abs();
    let p = if m % 2.0 == 0.0 {
        let a = abs(x);
        out(a.lo.powf(m), a.hi.powf(m))
    } else {
        up(x, |v| v.powf(m))
    };
    if n < 0.0 {
        div(Interval::point(1.0), p)
    } else {
        p
    }
}

pub(super) fn pow(x: Interval, y: Interval) -> Interval {
    if y.is_point() && y.lo == y.lo.trunc() && y.lo.abs() <= 1e6 {
        return powi(x, y.lo);
    }
    if x.lo < 0.0 || !(x.lo.is_finite() && x.hi.is_finite() && y.lo.is_finite() && y.hi.is_finite())
    {
        return Interval::ENTIRE;
    }
    // y ln x is bilinear in (ln x, y): its extremes, and so the power's, lie at the corners.
    span(&[
        x.lo.powf(y.lo),
        x.lo.powf(y.hi),
        x.hi.powf(y.lo),
        x.hi.powf(y.hi),
    ])
}

fn modulo(x: Interval, y: Interval) -> Interval {
    if y.contains(0.0) || !(x.lo.is_finite() && x.hi.is_finite()) {
        return Interval::ENTIRE;
    }
    if y.is_point() {
        // Within one cell of the truncated quotient the remainder is x - k y: increasing.
        let (qa, qb) = ((x.lo / y.lo).trunc(), (x.hi / y.lo).trunc());
        if qa == qb && (x.lo >= 0.0 || x.hi <= 0.0) {
            return out(x.lo % y.lo, x.hi % y.lo);
        }
    }
    let m = y.lo.abs().max(y.hi.abs());
    let lo = if x.lo >= 0.0 { 0.0 } else { x.lo.max(-m) };
    let hi = if x.hi <= 0.0 { 0.0 } else { x.hi.min(m) };
    out(lo, hi)
}

fn atan2(y: Interval, x: Interval) -> Interval {
    let full = Interval { lo: -PI, hi: PI };
    // The box holds the origin or meets the branch cut along the negative x axis.
    if y.contains(0.0) && x.lo <= 0.0 {
        return full;
    }
    if !(x.lo.is_finite() && x.hi.is_finite() && y.lo.is_finite() && y.hi.is_finite()) {
        return full;
    }
    // Away from the origin and the cut, the angle's extremes lie at the box's corners.
    let r = span(&[
        y.lo.atan2(x.lo),
        y.lo.atan2(x.hi),
        y.hi.atan2(x.lo),
        y.hi.atan2(x.hi),
    ]);
    Interval {
        lo: r.lo.max(-PI),
        hi: r.hi.min(PI),
    }
}

pub(super) fn unary(u: Unary, x: Interval) -> Interval {
    use Unary::*;
    match u {
        Neg => Interval {
            lo: -x.hi,
            hi: -x.lo,
        },
        Not => truth(x.is_point() && x.lo == 0.0, !x.contains(0.0)),
        Sin => sin(x),
        Cos => sin(Interval::new(x.lo + FRAC_PI_2, x.hi + FRAC_PI_2)),
        Tan => {
            if !(x.lo.is_finite() && x.hi.is_finite())
                || x.hi - x.lo >= PI
                || holds_phase(x, FRAC_PI_2, PI)
            {
                Interval::ENTIRE
            } else {
                up(x, f64::tan)
            }
        }
        Asin if x.lo >= -1.0 && x.hi <= 1.0 => up(x, f64::asin),
        Acos if x.lo >= -1.0 && x.hi <= 1.0 => out(x.hi.acos(), x.lo.acos()),
        Atanh if x.lo > -1.0 && x.hi < 1.0 => up(x, f64::atanh),
        Acosh if x.lo >= 1.0 => up(x, f64::acosh),
        Sqrt if x.lo >= 0.0 => up(x, f64::sqrt),
        Ln if x.lo > 0.0 => up(x, f64::ln),
        Log if x.lo > 0.0 => up(x, f64::log10),
        Asin | Acos | Atanh | Acosh | Sqrt | Ln | Log => Interval::ENTIRE,
        Atan => up(x, f64::atan),
        Sinh => up(x, f64::sinh),
        Tanh => up(x, f64::tanh),
        Asinh => up(x, f64::asinh),
        Exp => up(x, f64::exp),
        Cosh => {
            let a = abs(x);
            out(a.lo.cosh(), a.hi.cosh())
        }
        Abs => abs(x),
        Floor => up(x, f64::floor),
        Ceil => up(x, f64::ceil),
        Int => up(x, f64::trunc),
        Radians => up(x, f64::to_radians),
        Degrees => up(x, f64::to_degrees),
    }
}

pub(super) fn binary(b: Binary, x: Interval, y: Interval) -> Interval {
    use Binary::*;
    // `==` as the language compares: within 1e-10.
    let apart = x.lo - y.hi >= 1e-10 || y.lo - x.hi >= 1e-10;
    let nonzero = |v: Interval| !v.contains(0.0);
    let zero = |v: Interval| v.is_point() && v.lo == 0.0;
    match b {
        Add => out(x.lo + y.lo, x.hi + y.hi),
        Sub => out(x.lo - y.hi, x.hi - y.lo),
        Mul => mul(x, y),
        Div => div(x, y),
        Lt => truth(x.hi < y.lo, x.lo >= y.hi),
        Le => truth(x.hi <= y.lo, x.lo > y.hi),
        Gt => truth(x.lo > y.hi, x.hi <= y.lo),
        Ge => truth(x.lo >= y.hi, x.hi < y.lo),
        Eq => truth(false, apart),
        Ne => truth(apart, false),
        And => truth(nonzero(x) && nonzero(y), zero(x) || zero(y)),
        Or => truth(nonzero(x) || nonzero(y), zero(x) && zero(y)),
        Atan2 => atan2(x, y),
        Pow => pow(x, y),
        Mod => modulo(x, y),
        IntDiv => up(div(x, y), f64::trunc),
    }
}

impl Function {
    /// An interval holding every value of the function over the box `args` (missing arguments
    /// read as 0, as [`Function::eval`]).
    pub fn eval_interval(&self, args: &[Interval]) -> Interval {
        self.with_scratch(Interval::point(0.0), |stack, slots, from| {
            self.run_interval(args, stack, slots, from)
        })
    }

    /// Runs `run` on a value stack, the slots and the stack's `from` marks (see
    /// `run_interval`), all filled with `zero` (`from` with `NO_SLOT`): on the call stack for a
    /// small function, allocated for a large one.
    pub(super) fn with_scratch<T: Copy, R>(
        &self,
        zero: T,
        run: impl FnOnce(&mut [T], &mut [T], &mut [u32]) -> R,
    ) -> R {
        if self.stack_size() <= SMALL && self.slots() <= SMALL {
            run(
                &mut [zero; SMALL],
                &mut [zero; SMALL],
                &mut [NO_SLOT; SMALL],
            )
        } else {
            run(
                &mut vec![zero; self.stack_size()],
                &mut vec![zero; self.slots()],
                &mut vec![NO_SLOT; self.stack_size()],
            )
        }
    }

    /// `from[i]`: the slot stack entry `i` was loaded from unchanged (`NO_SLOT`: computed), so
    /// that `x * x` is a square (never negative) rather than a product of two independent
    /// ranges.
    fn run_interval(
        &self,
        args: &[Interval],
        stack: &mut [Interval],
        slots: &mut [Interval],
        from: &mut [u32],
    ) -> Interval {
        for (s, a) in slots[..self.params()].iter_mut().zip(args) {
            *s = *a;
        }
        let mut sp = 0;
        for op in self.code() {
            match op {
                Op::Const(c) => {
                    stack[sp] = Interval::point(*c);
                    sp += 1;
                }
                Op::Load(s) => {
                    stack[sp] = slots[*s as usize];
                    from[sp] = *s;
                    sp += 1;
                    continue;
                }
                Op::Store(s) => {
                    sp -= 1;
                    slots[*s as usize] = stack[sp];
                    continue;
                }
                Op::Unary(u) => stack[sp - 1] = unary(*u, stack[sp - 1]),
                Op::Binary(b) => {
                    sp -= 1;
                    let same = from[sp - 1] != NO_SLOT && from[sp - 1] == from[sp];
                    stack[sp - 1] = if *b == Binary::Mul && same {
                        powi(stack[sp], 2.0)
                    } else {
                        binary(*b, stack[sp - 1], stack[sp])
                    };
                }
                Op::Min(n) | Op::Max(n) => {
                    let start = sp - *n as usize;
                    let mut v = stack[start];
                    for x in &stack[start + 1..sp] {
                        v = if matches!(op, Op::Min(_)) {
                            Interval {
                                lo: v.lo.min(x.lo),
                                hi: v.hi.min(x.hi),
                            }
                        } else {
                            Interval {
                                lo: v.lo.max(x.lo),
                                hi: v.hi.max(x.hi),
                            }
                        };
                    }
                    stack[start] = v;
                    sp = start + 1;
                }
                Op::Select3 => {
                    sp -= 2;
                    let (a, b, c) = (stack[sp - 1], stack[sp], stack[sp + 1]);
                    stack[sp - 1] = if a.hi < 0.0 {
                        b
                    } else if a.lo >= 0.0 {
                        c
                    } else {
                        b.hull(c)
                    };
                }
                Op::Select4 => {
                    sp -= 3;
                    let (a, b, c, d) = (stack[sp - 1], stack[sp], stack[sp + 1], stack[sp + 2]);
                    let mut r: Option<Interval> = None;
                    let mut take = |v: Interval| r = Some(r.map_or(v, |h| h.hull(v)));
                    if a.lo < 0.0 {
                        take(b);
                    }
                    if a.contains(0.0) {
                        take(c);
                    }
                    if a.hi > 0.0 {
                        take(d);
                    }
                    stack[sp - 1] = r.unwrap_or(Interval::ENTIRE);
                }
                Op::Pattern(_) => {
                    sp -= 2;
                    stack[sp - 1] = Interval::UNIT;
                }
            }
            // Every other operation leaves a computed value on top.
            from[sp - 1] = NO_SLOT;
        }
        stack[0]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::function::{binary as fbinary, unary as funary};

    /// Deterministic points of `[lo, hi]`, ends included.
    fn samples(x: Interval) -> impl Iterator<Item = f64> {
        (0..=64).map(move |k| (x.lo + (x.hi - x.lo) * f64::from(k) / 64.0).clamp(x.lo, x.hi))
    }

    fn boxes() -> Vec<Interval> {
        let mut v = Vec::new();
        let ends = [
            -7.3, -2.0, -1.0, -0.5, -1e-3, 0.0, 0.25, 0.9, 1.0, 1.5, 3.0, 10.0,
        ];
        for &a in &ends {
            for &b in &ends {
                if a <= b {
                    v.push(Interval { lo: a, hi: b });
                }
            }
        }
        v
    }

    #[test]
    fn every_unary_image_holds_the_sampled_values() {
        use Unary::*;
        for u in [
            Neg, Not, Sin, Cos, Tan, Asin, Acos, Atan, Sinh, Cosh, Tanh, Asinh, Acosh, Atanh, Sqrt,
            Exp, Ln, Log, Abs, Floor, Ceil, Int, Radians, Degrees,
        ] {
            for x in boxes() {
                let r = unary(u, x);
                for v in samples(x) {
                    let f = funary(u, v);
                    if f.is_nan() {
                        assert_eq!(r, Interval::ENTIRE, "{u:?} {x:?} at {v}: NaN possible");
                    } else {
                        assert!(r.contains(f), "{u:?} over {x:?}: {f} at {v} not in {r:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn every_binary_image_holds_the_sampled_values() {
        use Binary::*;
        for b in [
            Add, Sub, Mul, Div, Lt, Le, Gt, Ge, Eq, Ne, And, Or, Atan2, Pow, Mod, IntDiv,
        ] {
            for x in boxes() {
                for y in boxes().into_iter().step_by(5).chain([
                    Interval::point(2.0),
                    Interval::point(3.0),
                    Interval::point(0.5),
                ]) {
                    let r = binary(b, x, y);
                    for u in samples(x).step_by(4) {
                        for v in samples(y).step_by(4) {
                            let f = fbinary(b, u, v);
                            if f.is_nan() {
                                assert_eq!(r, Interval::ENTIRE, "{b:?} {x:?} {y:?} at {u}, {v}");
                            } else if f.is_finite() {
                                assert!(
                                    r.contains(f),
                                    "{b:?} {x:?} {y:?}: {f} at {u}, {v} not in {r:?}"
                                );
                            }
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn narrow_sines_are_tight_and_the_pole_of_tan_is_unknown() {
        let r = unary(Unary::Sin, Interval { lo: 0.1, hi: 0.2 });
        assert!(r.lo > 0.09 && r.hi < 0.2, "{r:?}");
        let r = unary(Unary::Sin, Interval { lo: 1.5, hi: 1.7 });
        assert_eq!(r.hi, 1.0);
        assert_eq!(
            unary(Unary::Tan, Interval { lo: 1.5, hi: 1.7 }),
            Interval::ENTIRE
        );
        // x^2 over [-1, 2] is [0, 4], not [-2, 4] as x * x gives.
        let r = pow(Interval { lo: -1.0, hi: 2.0 }, Interval::point(2.0));
        assert!(
            r.lo <= 0.0 && r.lo > -1e-300 && (r.hi - 4.0).abs() < 1e-12,
            "{r:?}"
        );
    }

    #[test]
    fn a_parameter_times_itself_is_a_square() {
        // x * x + 1 over x in [-1, 2]: [1, 5], not [-1, 5]; x * y stays a product.
        let sq = Function::new(
            2,
            2,
            vec![
                Op::Load(0),
                Op::Load(0),
                Op::Binary(Binary::Mul),
                Op::Const(1.0),
                Op::Binary(Binary::Add),
            ],
        )
        .unwrap();
        let x = Interval { lo: -1.0, hi: 2.0 };
        let r = sq.eval_interval(&[x, x]);
        assert!(
            r.lo > 0.99 && r.lo <= 1.0 && r.hi >= 5.0 && r.hi < 5.01,
            "{r:?}"
        );
        let xy = Function::new(
            2,
            2,
            vec![Op::Load(0), Op::Load(1), Op::Binary(Binary::Mul)],
        )
        .unwrap();
        let r = xy.eval_interval(&[x, x]);
        assert!(r.lo <= -2.0, "{r:?}");
    }
}
