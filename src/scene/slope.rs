//! Interval slopes of a compiled [`Function`] along a line: for the box a stretch of a ray
//! sweeps and the ray's direction, an interval of the function's values (the same as
//! [`Function::eval_interval`]) and an interval holding its derivative along the ray there,
//! by forward differentiation in interval arithmetic. Where the derivative's interval excludes
//! 0 the function is strictly monotone on the stretch, so it crosses a threshold there at most
//! once: the isosurface's root finder then needs no more interval evaluations on it.
//!
//! The derivative is only claimed where the function is continuous on the whole box: an
//! operation that may jump there (a comparison, `floor`, `mod`, `select` or `atan2` across
//! their jumps, a pattern) or give no number (a value interval with an infinite end) makes it
//! the whole line, which never excludes 0.

use std::f64::consts::LN_10;

use super::Function;
use super::function::{Binary, Op, Unary};
use super::interval::{Interval, NO_SLOT, binary, div, mul, powi, unary};

const ZERO: Interval = Interval { lo: 0.0, hi: 0.0 };
const ONE: Interval = Interval { lo: 1.0, hi: 1.0 };

fn add(x: Interval, y: Interval) -> Interval {
    binary(Binary::Add, x, y)
}

fn sub(x: Interval, y: Interval) -> Interval {
    binary(Binary::Sub, x, y)
}

fn neg(x: Interval) -> Interval {
    unary(Unary::Neg, x)
}

fn sq(x: Interval) -> Interval {
    powi(x, 2.0)
}

fn scale(x: Interval, k: f64) -> Interval {
    mul(x, Interval::point(k))
}

/// 0 where `f` (a step function) takes one value over `x`, unknown where it may jump.
fn step(x: Interval, f: fn(f64) -> f64) -> Interval {
    if x.lo.is_finite() && x.hi.is_finite() && f(x.lo) == f(x.hi) {
        ZERO
    } else {
        Interval::ENTIRE
    }
}

/// 0 where a comparison or logic operation is decided (a point), unknown where it is not.
fn decided(v: Interval) -> Interval {
    if v.is_point() { ZERO } else { Interval::ENTIRE }
}

/// The derivative of `u(x)`, `x` having the derivative `dx`.
fn d_unary(u: Unary, x: Interval, dx: Interval) -> Interval {
    use Unary::*;
    match u {
        Neg => neg(dx),
        Sin => mul(unary(Cos, x), dx),
        Cos => mul(neg(unary(Sin, x)), dx),
        Tan => mul(add(ONE, sq(unary(Tan, x))), dx),
        Asin => div(dx, unary(Sqrt, sub(ONE, sq(x)))),
        Acos => neg(div(dx, unary(Sqrt, sub(ONE, sq(x))))),
        Atan => div(dx, add(ONE, sq(x))),
        Sinh => mul(unary(Cosh, x), dx),
        Cosh => mul(unary(Sinh, x), dx),
        Tanh => mul(sub(ONE, sq(unary(Tanh, x))), dx),
        Asinh => div(dx, unary(Sqrt, add(sq(x), ONE))),
        Acosh => div(dx, unary(Sqrt, sub(sq(x), ONE))),
        Atanh => div(dx, sub(ONE, sq(x))),
        Sqrt => div(dx, scale(unary(Sqrt, x), 2.0)),
        Exp => mul(unary(Exp, x), dx),
        Ln => div(dx, x),
        Log => div(dx, scale(x, LN_10)),
        // Not differentiable at 0, but Lipschitz: the slopes of both branches bound it.
        Abs if x.lo >= 0.0 => dx,
        Abs if x.hi <= 0.0 => neg(dx),
        Abs => {
            let m = dx.lo.abs().max(dx.hi.abs());
            Interval { lo: -m, hi: m }
        }
        Floor => step(x, f64::floor),
        Ceil => step(x, f64::ceil),
        Int => step(x, f64::trunc),
        Not => decided(unary(Not, x)),
        // Linear and increasing: the image of the derivative.
        Radians | Degrees => unary(u, dx),
    }
}

/// The derivative of `b(x, y)`, with `x`, `y` of derivatives `dx`, `dy` (`square`: `y` is
/// `x` loaded again, so that `x * y` is `x^2`).
fn d_binary(
    b: Binary,
    (x, dx): (Interval, Interval),
    (y, dy): (Interval, Interval),
    square: bool,
) -> Interval {
    use Binary::*;
    match b {
        Add => add(dx, dy),
        Sub => sub(dx, dy),
        Mul if square => scale(mul(x, dx), 2.0),
        Mul => add(mul(x, dy), mul(y, dx)),
        Div => div(sub(mul(dx, y), mul(x, dy)), sq(y)),
        Lt | Le | Gt | Ge | Eq | Ne | And | Or => decided(binary(b, x, y)),
        Atan2 => {
            // atan2(x, y): the angle of the point (y, x), which jumps across the cut along
            // y < 0 at x = 0.
            if x.contains(0.0) && y.lo <= 0.0 {
                Interval::ENTIRE
            } else {
                div(sub(mul(y, dx), mul(x, dy)), add(sq(x), sq(y)))
            }
        }
        Pow if y.is_point() && dy == ZERO => {
            let n = y.lo;
            if n == 0.0 {
                ZERO
            } else if n == n.trunc() && n.abs() <= 1e6 {
                mul(scale(powi(x, n - 1.0), n), dx)
            } else if x.lo > 0.0 {
                mul(scale(binary(Pow, x, Interval::point(n - 1.0)), n), dx)
            } else {
                Interval::ENTIRE
            }
        }
        // x^y = exp(y ln x): (y' ln x + y x' / x) x^y.
        Pow if x.lo > 0.0 => mul(
            binary(Pow, x, y),
            add(mul(dy, unary(Unary::Ln, x)), div(mul(y, dx), x)),
        ),
        Pow => Interval::ENTIRE,
        // Within one cell of the truncated quotient, x mod c is x - k c.
        Mod if y.is_point()
            && dy == ZERO
            && y.lo != 0.0
            && (x.lo >= 0.0 || x.hi <= 0.0)
            && (x.lo / y.lo).trunc() == (x.hi / y.lo).trunc() =>
        {
            dx
        }
        Mod => Interval::ENTIRE,
        IntDiv => step(div(x, y), f64::trunc),
    }
}

impl Function {
    /// The function's values over the box `args` ([`Function::eval_interval`]'s interval) and
    /// an interval of its derivative along the line through the box whose arguments change at
    /// the rates `rates` (a ray's direction); the whole line where it has none (see the
    /// module's notes).
    pub fn eval_slope(&self, args: &[Interval], rates: &[f64]) -> (Interval, Interval) {
        self.with_scratch((Interval::point(0.0), ZERO), |stack, slots, from| {
            self.run_slope(args, rates, stack, slots, from)
        })
    }

    /// [`Function::eval_slope`] on pairs (value, derivative); `from` as in `run_interval`.
    fn run_slope(
        &self,
        args: &[Interval],
        rates: &[f64],
        stack: &mut [(Interval, Interval)],
        slots: &mut [(Interval, Interval)],
        from: &mut [u32],
    ) -> (Interval, Interval) {
        for (k, s) in slots[..self.params()].iter_mut().enumerate() {
            *s = (
                args.get(k).copied().unwrap_or(Interval::point(0.0)),
                Interval::point(rates.get(k).copied().unwrap_or(0.0)),
            );
        }
        let mut sp = 0;
        for op in self.code() {
            match op {
                Op::Const(c) => {
                    stack[sp] = (Interval::point(*c), ZERO);
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
                Op::Unary(u) => {
                    let (x, dx) = stack[sp - 1];
                    stack[sp - 1] = (unary(*u, x), d_unary(*u, x, dx));
                }
                Op::Binary(b) => {
                    sp -= 1;
                    let square =
                        *b == Binary::Mul && from[sp - 1] != NO_SLOT && from[sp - 1] == from[sp];
                    let (x, y) = (stack[sp - 1], stack[sp]);
                    let v = if square {
                        powi(y.0, 2.0)
                    } else {
                        binary(*b, x.0, y.0)
                    };
                    stack[sp - 1] = (v, d_binary(*b, x, y, square));
                }
                Op::Min(n) | Op::Max(n) => {
                    let start = sp - *n as usize;
                    let xs = &stack[start..sp];
                    let min = matches!(op, Op::Min(_));
                    let mut v = xs[0].0;
                    for x in &xs[1..] {
                        v = if min {
                            Interval {
                                lo: v.lo.min(x.0.lo),
                                hi: v.hi.min(x.0.hi),
                            }
                        } else {
                            Interval {
                                lo: v.lo.max(x.0.lo),
                                hi: v.hi.max(x.0.hi),
                            }
                        };
                    }
                    // The slopes of the operands that can be the least (greatest) somewhere.
                    let mut d: Option<Interval> = None;
                    for x in xs {
                        let can = if min { x.0.lo <= v.hi } else { x.0.hi >= v.lo };
                        if can {
                            d = Some(d.map_or(x.1, |h| h.hull(x.1)));
                        }
                    }
                    stack[start] = (v, d.unwrap_or(Interval::ENTIRE));
                    sp = start + 1;
                }
                Op::Select3 => {
                    sp -= 2;
                    let (a, b, c) = (stack[sp - 1].0, stack[sp], stack[sp + 1]);
                    stack[sp - 1] = if a.hi < 0.0 {
                        b
                    } else if a.lo >= 0.0 {
                        c
                    } else {
                        (b.0.hull(c.0), Interval::ENTIRE)
                    };
                }
                Op::Select4 => {
                    sp -= 3;
                    let a = stack[sp - 1].0;
                    let branches = [
                        (a.lo < 0.0, stack[sp]),
                        (a.contains(0.0), stack[sp + 1]),
                        (a.hi > 0.0, stack[sp + 2]),
                    ];
                    let mut reached = branches.iter().filter(|b| b.0).map(|b| b.1);
                    stack[sp - 1] = match (reached.next(), reached.next()) {
                        (Some(only), None) => only,
                        (Some(first), Some(second)) => {
                            let v = reached.fold(first.0.hull(second.0), |h, b| h.hull(b.0));
                            (v, Interval::ENTIRE)
                        }
                        (None, _) => (Interval::ENTIRE, Interval::ENTIRE),
                    };
                }
                Op::Pattern(_) => {
                    sp -= 2;
                    stack[sp - 1] = (Interval { lo: 0.0, hi: 1.0 }, Interval::ENTIRE);
                }
            }
            // A value with no finite bound: nothing is known of its slope.
            let top = &mut stack[sp - 1];
            if !(top.0.lo.is_finite() && top.0.hi.is_finite()) {
                top.1 = Interval::ENTIRE;
            }
            from[sp - 1] = NO_SLOT;
        }
        stack[0]
    }
}

/// The derivative of `f` at `t` along `x(t)` by a central difference (for tests).
#[cfg(test)]
fn numeric(f: &Function, at: &[f64], rates: &[f64]) -> f64 {
    let h = 1e-6;
    let p = |s: f64| -> Vec<f64> { at.iter().zip(rates).map(|(a, r)| a + s * r).collect() };
    (f.eval(&p(h)) - f.eval(&p(-h))) / (2.0 * h)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Programs of two parameters, each using one operation on smooth and on stepped inputs.
    fn programs() -> Vec<(&'static str, Vec<Op>)> {
        use Binary as B;
        use Unary as U;
        let un = |u: Unary, inner: Vec<Op>| {
            let mut c = inner;
            c.push(Op::Unary(u));
            c
        };
        // A smooth argument in the domain of most functions: 0.3 + 0.2 sin(x + 2 y).
        let arg = || {
            vec![
                Op::Const(0.3),
                Op::Const(0.2),
                Op::Load(0),
                Op::Const(2.0),
                Op::Load(1),
                Op::Binary(B::Mul),
                Op::Binary(B::Add),
                Op::Unary(U::Sin),
                Op::Binary(B::Mul),
                Op::Binary(B::Add),
            ]
        };
        let mut v = Vec::new();
        for u in [
            U::Neg,
            U::Sin,
            U::Cos,
            U::Tan,
            U::Asin,
            U::Acos,
            U::Atan,
            U::Sinh,
            U::Cosh,
            U::Tanh,
            U::Asinh,
            U::Atanh,
            U::Sqrt,
            U::Exp,
            U::Ln,
            U::Log,
            U::Abs,
            U::Floor,
            U::Radians,
        ] {
            v.push(("unary", un(u, arg())));
        }
        // acosh needs an argument of at least 1.
        let mut c = arg();
        c.extend([Op::Const(1.5), Op::Binary(B::Add), Op::Unary(U::Acosh)]);
        v.push(("acosh", c));
        for b in [
            B::Add,
            B::Sub,
            B::Mul,
            B::Div,
            B::Pow,
            B::Atan2,
            B::Mod,
            B::Lt,
        ] {
            let mut c = arg();
            c.extend([Op::Load(1), Op::Const(1.7), Op::Binary(B::Add)]);
            c.push(Op::Binary(b));
            v.push(("binary", c));
        }
        // x * x (a square), x^2.5, min and max, select.
        v.push(("square", vec![Op::Load(0), Op::Load(0), Op::Binary(B::Mul)]));
        let mut c = arg();
        c.extend([Op::Const(2.5), Op::Binary(B::Pow)]);
        v.push(("pow", c));
        let mut c = arg();
        c.extend([Op::Load(1), Op::Load(0), Op::Min(3)]);
        v.push(("min", c));
        let mut c = arg();
        c.extend([Op::Load(1), Op::Max(2)]);
        v.push(("max", c));
        let mut c = vec![Op::Load(0)];
        c.extend(arg());
        c.extend([Op::Load(1), Op::Select3]);
        v.push(("select", c));
        v
    }

    /// On boxes along random lines, the derivative's interval holds the sampled derivatives,
    /// and where it excludes 0 the sampled values are monotone.
    #[test]
    fn slopes_hold_the_sampled_derivatives() {
        let mut seed = 0x51_09e5u64;
        let mut rand = || {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut monotone = 0;
        for (name, code) in programs() {
            let f = Function::new(2, 2, code).unwrap();
            for _ in 0..300 {
                let o = [rand() * 4.0 - 2.0, rand() * 4.0 - 2.0];
                let d = [rand() * 2.0 - 1.0, rand() * 2.0 - 1.0];
                let w = [1.0, 0.1, 1e-3][(rand() * 3.0) as usize];
                let at = |t: f64| [o[0] + t * d[0], o[1] + t * d[1]];
                let (a, b) = (at(0.0), at(w));
                let args = [Interval::new(a[0], b[0]), Interval::new(a[1], b[1])];
                let (value, slope) = f.eval_slope(&args, &d);
                assert_eq!(value, f.eval_interval(&args), "{name}");
                let mut last = f.eval(&at(0.0));
                for k in 1..=32 {
                    let t = w * f64::from(k) / 32.0;
                    let x = f.eval(&at(t));
                    // A slope that excludes 0: the values only rise (fall) along the line.
                    assert!(
                        !(slope.lo > 0.0 && x < last || slope.hi < 0.0 && x > last),
                        "{name}: {last} then {x} under a slope {slope:?}"
                    );
                    last = x;
                    let s = numeric(&f, &at(t - w / 64.0), &d);
                    if s.is_finite() {
                        let pad = 1e-5 * (1.0 + s.abs());
                        assert!(
                            slope.lo - pad <= s && s <= slope.hi + pad,
                            "{name} at {:?}: slope {s} not in {slope:?}",
                            at(t - w / 64.0)
                        );
                    }
                }
                if !slope.contains(0.0) {
                    monotone += 1;
                }
            }
        }
        assert!(
            monotone > 1000,
            "{monotone} monotone boxes: too few to test"
        );
    }
}
