//! Random streams, as POV-Ray's: `seed(n)` makes a stream, `rand(S)` draws the next number in
//! [0, 1) from the stream the variable `S` holds and advances it; `RRand`, `VRand`,
//! `VRand_In_Sphere`, `VRand_On_Sphere` and `Rand_Normal` are the helpers of POV-Ray's
//! `rand.inc`, built in. A stream is splitmix64 seeded from the whole part of `n` only (no
//! clock, no thread), so a scene draws the same numbers on every machine and every run; they
//! are not POV-Ray's own numbers. `Rand_Normal`'s logarithm and cosine come from `libm`, whose
//! results do not depend on the platform's maths library.

use std::cell::RefCell;
use std::f64::consts::PI;
use std::rc::Rc;

use glam::DVec3;

use super::Evaluator;
use super::value::Value;
use crate::diag::{At, Error, SourceResult, short_number};
use crate::sampling::SplitMix64;
use crate::span::Span;
use crate::syntax::ast::{Expr, ExprKind, Name};

/// The random functions, with their parameters as a call writes them.
pub(super) const RANDOM_FUNCTIONS: &[(&str, &str)] = &[
    ("seed", "N"),
    ("rand", "S"),
    ("RRand", "Min, Max, S"),
    ("VRand", "S"),
    ("VRand_In_Sphere", "S"),
    ("VRand_On_Sphere", "S"),
    ("Rand_Normal", "Mu, Sigma, S"),
];

/// The stream `seed(n)` makes: splitmix64 from the whole part of `n` (mixed, so that
/// neighbouring seeds give unrelated streams).
pub(super) fn stream(n: f64) -> SplitMix64 {
    SplitMix64::for_item(n.trunc() as i64 as u64, 0, 0)
}

/// A point uniform in the unit ball (rejection from the cube, as `rand.inc` does).
fn in_sphere(r: &mut SplitMix64) -> DVec3 {
    loop {
        let v = DVec3::new(r.range(-1.0, 1.0), r.range(-1.0, 1.0), r.range(-1.0, 1.0));
        if v.length_squared() < 1.0 {
            return v;
        }
    }
}

/// A standard normal deviate (Box-Muller).
fn normal(r: &mut SplitMix64) -> f64 {
    // 1 - u is in (0, 1]: its logarithm is finite.
    let u1 = 1.0 - r.f();
    let u2 = r.f();
    libm::sqrt(-2.0 * libm::log(u1)) * libm::cos(2.0 * PI * u2)
}

impl Evaluator {
    /// Calls random function `name`; `None` when it is none of [`RANDOM_FUNCTIONS`].
    pub(super) fn call_random(
        &mut self,
        name: &Name,
        args: &[Expr],
        span: Span,
    ) -> Option<SourceResult<Value>> {
        let (_, params) = RANDOM_FUNCTIONS.iter().find(|(n, _)| *n == name.text)?;
        Some(self.random(&name.text, params, args, span))
    }

    fn random(
        &mut self,
        name: &str,
        params: &str,
        args: &[Expr],
        span: Span,
    ) -> SourceResult<Value> {
        let arity = params.split(", ").count();
        if args.len() != arity {
            return Err(vec![
                Error::new(format!(
                    "`{name}` takes {arity} argument{}, found {}",
                    if arity == 1 { "" } else { "s" },
                    args.len()
                ))
                .label("wrong number of arguments")
                .help(format!("call it as `{name}({params})`"))
                .at(span),
            ]);
        }
        if name == "seed" {
            let n = self.eval(&args[0])?.num().at(args[0].span)?;
            return Ok(Value::Stream(Rc::new(RefCell::new(stream(n)))));
        }
        // The numbers first, then the stream (the last argument).
        let mut xs = Vec::with_capacity(2);
        for a in &args[..arity - 1] {
            xs.push(self.eval(a)?.num().at(a.span)?);
        }
        let s = self.stream_arg(name, params, &args[arity - 1])?;
        let mut guard = s.borrow_mut();
        let r = &mut *guard;
        Ok(match name {
            "rand" => Value::Num(r.f()),
            "RRand" => {
                let (lo, hi) = (xs[0], xs[1]);
                if lo > hi {
                    let (a, b) = (short_number(lo), short_number(hi));
                    return Err(vec![
                        Error::new(format!("`RRand` bounds are reversed ({a} > {b})"))
                            .label("the lower bound comes first")
                            .help(format!("write `RRand({b}, {a}, S)`"))
                            .at(args[0].span.join(args[1].span)),
                    ]);
                }
                // (Clamped: rounding could carry a draw just below 1 onto `hi`.)
                Value::Num((lo + (hi - lo) * r.f()).min(hi))
            }
            "VRand" => Value::Vec3(DVec3::new(r.f(), r.f(), r.f())),
            "VRand_In_Sphere" => Value::Vec3(in_sphere(r)),
            "VRand_On_Sphere" => Value::Vec3(r.unit()),
            "Rand_Normal" => {
                let (mu, sigma) = (xs[0], xs[1]);
                if sigma < 0.0 {
                    return Err(vec![
                        Error::new(format!(
                            "`Rand_Normal` needs a standard deviation of at least 0, found {}",
                            short_number(sigma)
                        ))
                        .label("negative")
                        .help("write `Rand_Normal(Mu, Sigma, S)` with Sigma ≥ 0")
                        .at(args[1].span),
                    ]);
                }
                Value::Num(mu + sigma * normal(r))
            }
            _ => unreachable!("random function {name}"),
        })
    }

    /// The stream a random function draws from: the one the variable `arg` holds.
    fn stream_arg(
        &mut self,
        name: &str,
        params: &str,
        arg: &Expr,
    ) -> SourceResult<Rc<RefCell<SplitMix64>>> {
        let example = format!("`#declare S = seed(42);` then `{name}({params})`");
        let ExprKind::Ident(var) = &arg.kind else {
            return Err(vec![
                Error::new(format!(
                    "`{name}` draws from a stream held by a variable, found an expression"
                ))
                .label("not a variable")
                .help(format!(
                    "declare the stream once and pass its name: {example}; each call advances \
                     the stream the variable holds (a stream made in the call would give the \
                     same number every time)"
                ))
                .at(arg.span),
            ]);
        };
        match self.lookup(var, arg.span)? {
            Value::Stream(s) => Ok(s),
            v => Err(vec![
                Error::new(format!(
                    "`{name}` needs a random stream, found {}",
                    v.type_name()
                ))
                .label("not a random stream")
                .help(format!("make one with `seed(n)`: {example}"))
                .at(arg.span),
            ]),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_seed_gives_one_stream_and_neighbouring_seeds_differ() {
        let draw = |n: f64| {
            let mut r = stream(n);
            (0..4).map(|_| r.f()).collect::<Vec<_>>()
        };
        assert_eq!(draw(42.0), draw(42.0));
        // The whole part only, as POV-Ray's `seed`.
        assert_eq!(draw(42.0), draw(42.9));
        assert_ne!(draw(42.0), draw(43.0));
        assert_ne!(draw(-1.0), draw(1.0));
    }

    #[test]
    fn normal_deviates_have_the_right_mean_and_spread() {
        let mut r = stream(7.0);
        let xs: Vec<f64> = (0..20_000).map(|_| normal(&mut r)).collect();
        let mean = xs.iter().sum::<f64>() / xs.len() as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / xs.len() as f64;
        // Standard errors: 0.007 for the mean, 0.01 for the variance; bounds at about 4.
        assert!(mean.abs() < 0.03, "{mean}");
        assert!((var - 1.0).abs() < 0.04, "{var}");
        assert!(xs.iter().all(|x| x.is_finite()));
    }
}
