//! Polynomials in the Bernstein basis on [0, 1].
//!
//! `p(t) = sum_i c_i * C(n, i) * t^i * (1 - t)^(n - i)`. The coefficients form a control polygon
//! whose convex hull contains the graph of `p` (the convex-hull property the root isolator relies
//! on). Degrees up to [`MAX_DEGREE`] are stored inline (no allocation in the hot path).

/// Highest degree stored: a degree-7 profile segment squared gives degree 14.
pub const MAX_DEGREE: usize = 15;

/// A polynomial of degree `n <= MAX_DEGREE` in the Bernstein basis on [0, 1].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bernstein {
    n: usize,
    c: [f64; MAX_DEGREE + 1],
}

/// Pascal's triangle up to `MAX_DEGREE`, exact in f64 (the largest entry is 6435).
const BINOMIAL: [[f64; MAX_DEGREE + 1]; MAX_DEGREE + 1] = {
    let mut t = [[0.0; MAX_DEGREE + 1]; MAX_DEGREE + 1];
    let mut n = 0;
    while n <= MAX_DEGREE {
        t[n][0] = 1.0;
        let mut k = 1;
        while k <= n {
            t[n][k] = t[n - 1][k - 1] + t[n - 1][k];
            k += 1;
        }
        n += 1;
    }
    t
};

fn binomial(n: usize, k: usize) -> f64 {
    BINOMIAL[n][k]
}

/// Calls `$f::<M>(args)` with `M = n + 1` (`n <= MAX_DEGREE`): de Casteljau's loops with
/// constant bounds for every degree, the same arithmetic as one loop over `n`.
macro_rules! by_degree {
    ($n:expr, $f:ident, $($arg:expr),*) => {
        match $n {
            0 => $f::<1>($($arg),*),
            1 => $f::<2>($($arg),*),
            2 => $f::<3>($($arg),*),
            3 => $f::<4>($($arg),*),
            4 => $f::<5>($($arg),*),
            5 => $f::<6>($($arg),*),
            6 => $f::<7>($($arg),*),
            7 => $f::<8>($($arg),*),
            8 => $f::<9>($($arg),*),
            9 => $f::<10>($($arg),*),
            10 => $f::<11>($($arg),*),
            11 => $f::<12>($($arg),*),
            12 => $f::<13>($($arg),*),
            13 => $f::<14>($($arg),*),
            14 => $f::<15>($($arg),*),
            _ => $f::<{ MAX_DEGREE + 1 }>($($arg),*),
        }
    };
}

impl Bernstein {
    /// From coefficients `c_0..=c_n`; `None` when there are none or more than `MAX_DEGREE + 1`.
    pub fn new(coeffs: &[f64]) -> Option<Self> {
        if coeffs.is_empty() || coeffs.len() > MAX_DEGREE + 1 {
            return None;
        }
        let mut c = [0.0; MAX_DEGREE + 1];
        c[..coeffs.len()].copy_from_slice(coeffs);
        Some(Self {
            n: coeffs.len() - 1,
            c,
        })
    }

    /// The constant polynomial `v`.
    pub fn constant(v: f64) -> Self {
        let mut c = [0.0; MAX_DEGREE + 1];
        c[0] = v;
        Self { n: 0, c }
    }

    pub fn degree(&self) -> usize {
        self.n
    }

    pub fn coeffs(&self) -> &[f64] {
        &self.c[..=self.n]
    }

    /// Largest absolute coefficient: a bound on `|p|` over [0, 1].
    #[inline]
    pub fn max_abs(&self) -> f64 {
        self.coeffs().iter().fold(0.0, |m, c| m.max(c.abs()))
    }

    /// Value at `t` by de Casteljau's algorithm (stable for t in [0, 1]). Cubics (the profiles'
    /// usual degree) inline, without the derivative: the same arithmetic as
    /// [`Bernstein::eval_with_derivative`].
    #[inline]
    pub fn eval(&self, t: f64) -> f64 {
        if self.n == 3 {
            let c = &self.c;
            let lerp = |a: f64, b: f64| a + t * (b - a);
            let (b0, b1, b2) = (lerp(c[0], c[1]), lerp(c[1], c[2]), lerp(c[2], c[3]));
            let (b0, b1) = (lerp(b0, b1), lerp(b1, b2));
            return lerp(b0, b1);
        }
        self.eval_with_derivative(t).0
    }

    /// Value and first derivative at `t` from one de Casteljau pass.
    pub fn eval_with_derivative(&self, t: f64) -> (f64, f64) {
        // The same arithmetic whatever the degree, in code specialised per degree.
        let c = &self.c;
        match self.n {
            0 => (c[0], 0.0),
            1 => (c[0] + t * (c[1] - c[0]), c[1] - c[0]),
            2 => {
                let lerp = |a: f64, b: f64| a + t * (b - a);
                let (b0, b1) = (lerp(c[0], c[1]), lerp(c[1], c[2]));
                (lerp(b0, b1), 2.0 * (b1 - b0))
            }
            3 => {
                // The pass of `casteljau` in local variables.
                let lerp = |a: f64, b: f64| a + t * (b - a);
                let (b0, b1, b2) = (lerp(c[0], c[1]), lerp(c[1], c[2]), lerp(c[2], c[3]));
                let (b0, b1) = (lerp(b0, b1), lerp(b1, b2));
                (lerp(b0, b1), 3.0 * (b1 - b0))
            }
            4 => casteljau::<5>(c, t),
            5 => casteljau::<6>(c, t),
            6 => {
                // A cubic profile's `F` (the polish's degree): the pass in local variables.
                let lerp = |a: f64, b: f64| a + t * (b - a);
                let (b0, b1, b2) = (lerp(c[0], c[1]), lerp(c[1], c[2]), lerp(c[2], c[3]));
                let (b3, b4, b5) = (lerp(c[3], c[4]), lerp(c[4], c[5]), lerp(c[5], c[6]));
                let (b0, b1, b2) = (lerp(b0, b1), lerp(b1, b2), lerp(b2, b3));
                let (b3, b4) = (lerp(b3, b4), lerp(b4, b5));
                let (b0, b1, b2, b3) = (lerp(b0, b1), lerp(b1, b2), lerp(b2, b3), lerp(b3, b4));
                let (b0, b1, b2) = (lerp(b0, b1), lerp(b1, b2), lerp(b2, b3));
                let (b0, b1) = (lerp(b0, b1), lerp(b1, b2));
                (lerp(b0, b1), 6.0 * (b1 - b0))
            }
            7 => casteljau::<8>(c, t),
            8 => casteljau::<9>(c, t),
            9 => casteljau::<10>(c, t),
            10 => casteljau::<11>(c, t),
            11 => casteljau::<12>(c, t),
            12 => casteljau::<13>(c, t),
            13 => casteljau::<14>(c, t),
            14 => casteljau::<15>(c, t),
            _ => casteljau::<{ MAX_DEGREE + 1 }>(c, t),
        }
    }

    /// Value, first and second derivative at `t` from one de Casteljau pass. The value and the
    /// first derivative are those of [`Bernstein::eval_with_derivative`], bit for bit; the
    /// second is `n (n - 1) (b_2 - 2 b_1 + b_0)` of the pass's level `n - 2`.
    pub fn eval_with_two_derivatives(&self, t: f64) -> (f64, f64, f64) {
        let c = &self.c;
        match self.n {
            0 | 1 => {
                let (v, d) = self.eval_with_derivative(t);
                (v, d, 0.0)
            }
            2 => casteljau2::<3>(c, t),
            3 => casteljau2::<4>(c, t),
            4 => casteljau2::<5>(c, t),
            5 => casteljau2::<6>(c, t),
            6 => casteljau2::<7>(c, t),
            7 => casteljau2::<8>(c, t),
            8 => casteljau2::<9>(c, t),
            9 => casteljau2::<10>(c, t),
            10 => casteljau2::<11>(c, t),
            11 => casteljau2::<12>(c, t),
            12 => casteljau2::<13>(c, t),
            13 => casteljau2::<14>(c, t),
            14 => casteljau2::<15>(c, t),
            _ => casteljau2::<{ MAX_DEGREE + 1 }>(c, t),
        }
    }

    /// A bound of `|p''|` on [0, 1]: `n (n - 1)` times the largest second difference of the
    /// coefficients (the second derivative's control polygon), computed in f64 (a relative
    /// rounding of a few ulps).
    pub fn second_derivative_bound(&self) -> f64 {
        let n = self.n;
        if n < 2 {
            return 0.0;
        }
        let c = &self.c;
        let mut m = 0.0f64;
        for i in 0..n - 1 {
            m = m.max((c[i + 2] - 2.0 * c[i + 1] + c[i]).abs());
        }
        (n * (n - 1)) as f64 * m
    }

    /// Splits at `t`: the left part reparameterised on [0, 1] covers [0, t], the right [t, 1].
    pub fn split(&self, t: f64) -> (Self, Self) {
        let mut left = *self;
        let mut right = *self;
        by_degree!(self.n, split_levels, &self.c, t, &mut left.c, &mut right.c);
        (left, right)
    }

    /// The part on [0, t] reparameterised on [0, 1] (the left half of [`Bernstein::split`],
    /// the same arithmetic).
    pub fn left_of(&self, t: f64) -> Self {
        let mut left = *self;
        by_degree!(self.n, left_levels, &self.c, t, &mut left.c);
        left
    }

    /// The part on [t, 1] reparameterised on [0, 1] (the right half of [`Bernstein::split`],
    /// the same arithmetic, in place).
    pub fn right_of(&self, t: f64) -> Self {
        let mut right = *self;
        by_degree!(self.n, right_levels, t, &mut right.c);
        right
    }

    /// The restriction to [a, b] reparameterised on [0, 1].
    pub fn restrict(&self, a: f64, b: f64) -> Self {
        if b >= 1.0 {
            return self.right_of(a);
        }
        let left = self.left_of(b);
        if a <= 0.0 { left } else { left.right_of(a / b) }
    }

    /// The derivative (degree n - 1; the zero constant for a constant).
    pub fn derivative(&self) -> Self {
        let n = self.n;
        if n == 0 {
            return Self::constant(0.0);
        }
        let mut c = [0.0; MAX_DEGREE + 1];
        for (i, ci) in c.iter_mut().enumerate().take(n) {
            *ci = n as f64 * (self.c[i + 1] - self.c[i]);
        }
        Self { n: n - 1, c }
    }

    /// The same polynomial one degree higher (`None` above `MAX_DEGREE`).
    pub fn elevate(&self) -> Option<Self> {
        let n = self.n;
        if n >= MAX_DEGREE {
            return None;
        }
        let mut c = [0.0; MAX_DEGREE + 1];
        c[0] = self.c[0];
        c[n + 1] = self.c[n];
        for (i, ci) in c.iter_mut().enumerate().take(n + 1).skip(1) {
            let a = i as f64 / (n + 1) as f64;
            *ci = a * self.c[i - 1] + (1.0 - a) * self.c[i];
        }
        Some(Self { n: n + 1, c })
    }

    /// Elevates to degree `m >= n`.
    pub fn elevate_to(&self, m: usize) -> Option<Self> {
        let mut p = *self;
        while p.n < m {
            p = p.elevate()?;
        }
        Some(p)
    }

    /// `self * s`.
    pub fn scale(&self, s: f64) -> Self {
        let mut p = *self;
        for c in &mut p.c[..=p.n] {
            *c *= s;
        }
        p
    }

    /// `self + v` for a constant `v` (adds `v` to every coefficient: partition of unity).
    pub fn add_constant(&self, v: f64) -> Self {
        let mut p = *self;
        for c in &mut p.c[..=p.n] {
            *c += v;
        }
        p
    }

    /// `self * s + v` for a constant `v`: [`Bernstein::scale`] then [`Bernstein::add_constant`]
    /// (the same operations) in one pass.
    #[inline]
    pub fn scale_add(&self, s: f64, v: f64) -> Self {
        let mut p = *self;
        for c in &mut p.c[..=p.n] {
            *c = *c * s + v;
        }
        p
    }

    /// `self + other` (the lower degree is elevated). `None` above `MAX_DEGREE`.
    pub fn add(&self, other: &Self) -> Option<Self> {
        let m = self.n.max(other.n);
        let a = self.elevate_to(m)?;
        let b = other.elevate_to(m)?;
        let mut p = a;
        for i in 0..=m {
            p.c[i] = a.c[i] + b.c[i];
        }
        Some(p)
    }

    /// `a^2 + b^2 + w c` for `a`, `b` of one degree `n` and `c` of degree `2n`, computed as
    /// `a.mul(&a)?.add(&b.mul(&b)?)?.add(&c.scale(w))` computes it (the same operations, bit for
    /// bit) without the intermediate values; other degrees go that way. `None` above
    /// `MAX_DEGREE`.
    #[inline]
    pub fn square_sum(a: &Self, b: &Self, c: &Self, w: f64) -> Option<Self> {
        let n = a.n;
        if b.n != n || c.n != 2 * n || 2 * n > MAX_DEGREE {
            return a.mul(a)?.add(&b.mul(b)?)?.add(&c.scale(w));
        }
        let (aa, bb) = (a.product_with(a), b.product_with(b));
        let mut f = [0.0; MAX_DEGREE + 1];
        for k in 0..=2 * n {
            f[k] = (aa[k] + bb[k]) + c.c[k] * w;
        }
        Some(Self { n: 2 * n, c: f })
    }

    /// [`Bernstein::square_sum`] for cubics `a`, `b` and a sextic `c` given by their
    /// coefficients: the same operations, on arrays of their own length.
    pub fn cubic_square_sum(a: &[f64; 4], b: &[f64; 4], c: &[f64; 7], w: f64) -> Self {
        let square = |p: &[f64; 4]| {
            let mut s = [0.0; 7];
            for i in 0..4 {
                let bi = binomial(3, i) * p[i];
                for j in 0..4 {
                    s[i + j] += bi * binomial(3, j) * p[j];
                }
            }
            for (k, sk) in s.iter_mut().enumerate() {
                *sk /= binomial(6, k);
            }
            s
        };
        let (aa, bb) = (square(a), square(b));
        let mut f = [0.0; MAX_DEGREE + 1];
        for k in 0..7 {
            f[k] = (aa[k] + bb[k]) + c[k] * w;
        }
        Self { n: 6, c: f }
    }

    /// `self * other` (degree n + m). `None` above `MAX_DEGREE`.
    pub fn mul(&self, other: &Self) -> Option<Self> {
        let (n, m) = (self.n, other.n);
        if n + m > MAX_DEGREE {
            return None;
        }
        Some(Self {
            n: n + m,
            c: self.product_with(other),
        })
    }

    /// The coefficients of `self * other` (`n + m <= MAX_DEGREE`). The squares of profile
    /// coordinates (equal low degrees) get loops of fixed bounds.
    #[inline]
    fn product_with(&self, other: &Self) -> [f64; MAX_DEGREE + 1] {
        match (self.n, other.n) {
            (1, 1) => product(1, 1, &self.c, &other.c),
            (2, 2) => product(2, 2, &self.c, &other.c),
            (3, 3) => product(3, 3, &self.c, &other.c),
            (n, m) => product(n, m, &self.c, &other.c),
        }
    }
}

/// The Bernstein coefficients of the product of the degree `n` and degree `m` polynomials with
/// the coefficients `a` and `b` (`n + m <= MAX_DEGREE`).
#[inline(always)]
fn product(
    n: usize,
    m: usize,
    a: &[f64; MAX_DEGREE + 1],
    b: &[f64; MAX_DEGREE + 1],
) -> [f64; MAX_DEGREE + 1] {
    let mut c = [0.0; MAX_DEGREE + 1];
    for i in 0..=n {
        let bi = binomial(n, i) * a[i];
        for j in 0..=m {
            c[i + j] += bi * binomial(m, j) * b[j];
        }
    }
    for (k, ck) in c.iter_mut().enumerate().take(n + m + 1) {
        *ck /= binomial(n + m, k);
    }
    c
}

/// De Casteljau's levels of the degree `M - 1` coefficients `c` at `t`: the left part's
/// coefficients into `left[..M]` and the right part's into `right[..M]`.
#[inline(always)]
fn split_levels<const M: usize>(
    c: &[f64; MAX_DEGREE + 1],
    t: f64,
    left: &mut [f64; MAX_DEGREE + 1],
    right: &mut [f64; MAX_DEGREE + 1],
) {
    let n = M - 1;
    let mut b = [0.0; M];
    b.copy_from_slice(&c[..M]);
    left[0] = b[0];
    right[n] = b[n];
    for level in 1..M {
        for i in 0..M - level {
            b[i] += t * (b[i + 1] - b[i]);
        }
        left[level] = b[0];
        right[n - level] = b[n - level];
    }
}

/// The left part only (see [`split_levels`]).
#[inline(always)]
fn left_levels<const M: usize>(
    c: &[f64; MAX_DEGREE + 1],
    t: f64,
    left: &mut [f64; MAX_DEGREE + 1],
) {
    let mut b = [0.0; M];
    b.copy_from_slice(&c[..M]);
    left[0] = b[0];
    // Index loops of constant bounds: an iterator chain here (enumerate, take, skip) was not
    // optimised away and cost three times the arithmetic.
    #[allow(clippy::needless_range_loop)]
    for level in 1..M {
        for i in 0..M - level {
            b[i] += t * (b[i + 1] - b[i]);
        }
        left[level] = b[0];
    }
}

/// The right part only, in place (see [`split_levels`]).
#[inline(always)]
fn right_levels<const M: usize>(t: f64, c: &mut [f64; MAX_DEGREE + 1]) {
    let mut b = [0.0; M];
    b.copy_from_slice(&c[..M]);
    for level in 1..M {
        for i in 0..M - level {
            b[i] += t * (b[i + 1] - b[i]);
        }
    }
    c[..M].copy_from_slice(&b);
}

/// Value and derivative of the degree `M - 1` polynomial (`M >= 2`) with coefficients `c[..M]`,
/// by de Casteljau's algorithm (a copy of the pass per degree, whose loop bounds are constants).
#[inline(always)]
fn casteljau<const M: usize>(c: &[f64; MAX_DEGREE + 1], t: f64) -> (f64, f64) {
    let mut b = [0.0; M];
    b.copy_from_slice(&c[..M]);
    // Degrees 4 and up keep the in-place update (a fresh array per level measured slower).
    let n = M - 1;
    for level in 1..n {
        for i in 0..=n - level {
            b[i] += t * (b[i + 1] - b[i]);
        }
    }
    let v = b[0] + t * (b[1] - b[0]);
    (v, n as f64 * (b[1] - b[0]))
}

/// Value, first and second derivative of the degree `M - 1` polynomial (`M >= 3`): the pass
/// of [`casteljau`], with the second derivative taken from level `n - 2`.
#[inline(always)]
fn casteljau2<const M: usize>(c: &[f64; MAX_DEGREE + 1], t: f64) -> (f64, f64, f64) {
    let mut b = [0.0; M];
    b.copy_from_slice(&c[..M]);
    let n = M - 1;
    for level in 1..n - 1 {
        for i in 0..=n - level {
            b[i] += t * (b[i + 1] - b[i]);
        }
    }
    let d2 = (n * (n - 1)) as f64 * (b[2] - 2.0 * b[1] + b[0]);
    // Level `n - 1` as `casteljau` computes it, then the value.
    b[0] += t * (b[1] - b[0]);
    b[1] += t * (b[2] - b[1]);
    let v = b[0] + t * (b[1] - b[0]);
    (v, n as f64 * (b[1] - b[0]), d2)
}

#[cfg(test)]
mod tests;
