//! A compiled user function (`function(x, y, z) { ... }`): a small postfix program over `f64`,
//! run on a value stack with no recursion and no allocation (for up to [`SMALL`] stack entries
//! and slots). The evaluator compiles a function once, with its declared constants folded and
//! the functions it calls inlined; anything that holds a [`Function`] (a `#declare`d value, a
//! shape later) evaluates it without the language.
//!
//! A program is checked when it is made ([`Function::new`]): every operation finds its operands
//! on the stack and every slot exists, so running it cannot fail. Arithmetic is `f64`'s: a
//! division by zero gives an infinity or NaN, and NaN and infinities pass through.

use glam::DVec3;

use super::pattern_value::PatternFn;

/// Most operations one function may have (after inlining the functions it calls): a function
/// calling another twice, which calls another twice, ... doubles with every level.
pub const MAX_OPS: usize = 1 << 16;

/// Stack entries and slots a run keeps on the Rust stack; a larger function allocates.
pub const SMALL: usize = 32;

/// How close two numbers are equal for `==` and `!=` (as the language's comparison).
const EQUAL_WITHIN: f64 = 1e-10;

/// Operations of one operand.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unary {
    Neg,
    Not,
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Sinh,
    Cosh,
    Tanh,
    Asinh,
    Acosh,
    Atanh,
    Sqrt,
    Exp,
    Ln,
    Log,
    Abs,
    Floor,
    Ceil,
    Int,
    Radians,
    Degrees,
}

/// Operations of two operands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Binary {
    Add,
    Sub,
    Mul,
    Div,
    Lt,
    Le,
    Gt,
    Ge,
    Eq,
    Ne,
    And,
    Or,
    Atan2,
    Pow,
    Mod,
    /// Whole quotient, truncated (POV-Ray's `div`).
    IntDiv,
}

/// The built-in functions a function body can call, with their operation: one argument.
pub const UNARY_NAMES: &[(&str, Unary)] = &[
    ("sin", Unary::Sin),
    ("cos", Unary::Cos),
    ("tan", Unary::Tan),
    ("asin", Unary::Asin),
    ("acos", Unary::Acos),
    ("atan", Unary::Atan),
    ("sinh", Unary::Sinh),
    ("cosh", Unary::Cosh),
    ("tanh", Unary::Tanh),
    ("asinh", Unary::Asinh),
    ("acosh", Unary::Acosh),
    ("atanh", Unary::Atanh),
    ("sqrt", Unary::Sqrt),
    ("exp", Unary::Exp),
    ("ln", Unary::Ln),
    ("log", Unary::Log),
    ("abs", Unary::Abs),
    ("floor", Unary::Floor),
    ("ceil", Unary::Ceil),
    ("int", Unary::Int),
    ("radians", Unary::Radians),
    ("degrees", Unary::Degrees),
];

/// Two arguments.
pub const BINARY_NAMES: &[(&str, Binary)] = &[
    ("atan2", Binary::Atan2),
    ("pow", Binary::Pow),
    ("mod", Binary::Mod),
    ("div", Binary::IntDiv),
];

/// One operation of a program.
#[derive(Debug, Clone, PartialEq)]
pub enum Op {
    Const(f64),
    /// Pushes a slot: a parameter (the first slots) or an inlined call's argument.
    Load(u32),
    /// Pops into a slot.
    Store(u32),
    Unary(Unary),
    Binary(Binary),
    /// Pops n ≥ 1 values, pushes their least (greatest).
    Min(u32),
    Max(u32),
    /// POV-Ray's `select(a, b, c)`: `b` if `a < 0`, else `c`.
    Select3,
    /// `select(a, b, c, d)`: `b` if `a < 0`, `c` if `a == 0`, else `d`.
    Select4,
    /// Pops z, y, x; pushes the pattern's value at that point.
    Pattern(Box<PatternFn>),
}

impl Op {
    /// Values the operation pops.
    fn pops(&self) -> usize {
        match self {
            Op::Const(_) | Op::Load(_) => 0,
            Op::Store(_) | Op::Unary(_) => 1,
            Op::Binary(_) => 2,
            Op::Min(n) | Op::Max(n) => *n as usize,
            Op::Select3 | Op::Pattern(_) => 3,
            Op::Select4 => 4,
        }
    }

    fn pushes(&self) -> usize {
        usize::from(!matches!(self, Op::Store(_)))
    }
}

/// Why a program was refused.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum FunctionError {
    /// More than [`MAX_OPS`] operations.
    TooLarge(usize),
    /// An operation without its operands, a slot out of range, or not one result at the end:
    /// a compiler's mistake, not the scene's.
    Malformed(String),
}

/// A checked program of `params` parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct Function {
    params: usize,
    slots: usize,
    stack: usize,
    code: Vec<Op>,
}

impl Function {
    /// The operations of one evaluation (calls to other functions included: the program is
    /// flat).
    pub fn ops(&self) -> usize {
        self.code.len()
    }

    /// Checks `code`, a program of `params` parameters using `slots` slots (parameters first).
    pub fn new(params: usize, slots: usize, code: Vec<Op>) -> Result<Function, FunctionError> {
        if code.len() > MAX_OPS {
            return Err(FunctionError::TooLarge(code.len()));
        }
        let bad = |m: String| Err(FunctionError::Malformed(m));
        if slots < params {
            return bad(format!("{slots} slots for {params} parameters"));
        }
        let (mut height, mut stack) = (0usize, 0usize);
        for (i, op) in code.iter().enumerate() {
            if let Op::Load(s) | Op::Store(s) = op
                && *s as usize >= slots
            {
                return bad(format!("operation {i} uses slot {s} of {slots}"));
            }
            if matches!(op, Op::Min(0) | Op::Max(0)) {
                return bad(format!("operation {i} takes no operands"));
            }
            if height < op.pops() {
                return bad(format!("operation {i} finds {height} operands"));
            }
            height = height - op.pops() + op.pushes();
            stack = stack.max(height);
        }
        if height != 1 {
            return bad(format!("the program leaves {height} values"));
        }
        Ok(Function {
            params,
            slots,
            stack,
            code,
        })
    }

    /// A function of no parameters that returns `c`.
    pub fn constant(c: f64) -> Function {
        Function {
            params: 0,
            slots: 0,
            stack: 1,
            code: vec![Op::Const(c)],
        }
    }

    pub fn params(&self) -> usize {
        self.params
    }

    pub fn slots(&self) -> usize {
        self.slots
    }

    /// Stack entries a run needs.
    pub fn stack_size(&self) -> usize {
        self.stack
    }

    pub fn code(&self) -> &[Op] {
        &self.code
    }

    /// The value at `args` (missing arguments read as 0, extra ones are ignored).
    pub fn eval(&self, args: &[f64]) -> f64 {
        if self.stack <= SMALL && self.slots <= SMALL {
            let mut stack = [0.0; SMALL];
            let mut slots = [0.0; SMALL];
            self.run(args, &mut stack, &mut slots)
        } else {
            self.run(args, &mut vec![0.0; self.stack], &mut vec![0.0; self.slots])
        }
    }

    /// The value at a point, for a function of (x, y, z).
    pub fn eval_point(&self, p: DVec3) -> f64 {
        self.eval(&[p.x, p.y, p.z])
    }

    fn run(&self, args: &[f64], stack: &mut [f64], slots: &mut [f64]) -> f64 {
        for (s, a) in slots[..self.params].iter_mut().zip(args) {
            *s = *a;
        }
        let mut sp = 0;
        for op in &self.code {
            match op {
                Op::Const(c) => {
                    stack[sp] = *c;
                    sp += 1;
                }
                Op::Load(s) => {
                    stack[sp] = slots[*s as usize];
                    sp += 1;
                }
                Op::Store(s) => {
                    sp -= 1;
                    slots[*s as usize] = stack[sp];
                }
                Op::Unary(u) => stack[sp - 1] = unary(*u, stack[sp - 1]),
                Op::Binary(b) => {
                    sp -= 1;
                    stack[sp - 1] = binary(*b, stack[sp - 1], stack[sp]);
                }
                Op::Min(n) | Op::Max(n) => {
                    let start = sp - *n as usize;
                    let xs = &stack[start..sp];
                    let v = if matches!(op, Op::Min(_)) {
                        xs.iter().copied().fold(f64::INFINITY, f64::min)
                    } else {
                        xs.iter().copied().fold(f64::NEG_INFINITY, f64::max)
                    };
                    stack[start] = v;
                    sp = start + 1;
                }
                Op::Select3 => {
                    sp -= 2;
                    let (a, b, c) = (stack[sp - 1], stack[sp], stack[sp + 1]);
                    stack[sp - 1] = if a < 0.0 { b } else { c };
                }
                Op::Select4 => {
                    sp -= 3;
                    let (a, b, c, d) = (stack[sp - 1], stack[sp], stack[sp + 1], stack[sp + 2]);
                    stack[sp - 1] = if a < 0.0 {
                        b
                    } else if a == 0.0 {
                        c
                    } else {
                        d
                    };
                }
                Op::Pattern(p) => {
                    sp -= 2;
                    let at = DVec3::new(stack[sp - 1], stack[sp], stack[sp + 1]);
                    stack[sp - 1] = p.value(at);
                }
            }
        }
        stack[0]
    }
}

fn truth(x: bool) -> f64 {
    if x { 1.0 } else { 0.0 }
}

/// One operand's operation, with `f64`'s meaning outside the domain (NaN).
pub fn unary(u: Unary, x: f64) -> f64 {
    match u {
        Unary::Neg => -x,
        Unary::Not => truth(x == 0.0),
        Unary::Sin => x.sin(),
        Unary::Cos => x.cos(),
        Unary::Tan => x.tan(),
        Unary::Asin => x.asin(),
        Unary::Acos => x.acos(),
        Unary::Atan => x.atan(),
        Unary::Sinh => x.sinh(),
        Unary::Cosh => x.cosh(),
        Unary::Tanh => x.tanh(),
        Unary::Asinh => x.asinh(),
        Unary::Acosh => x.acosh(),
        Unary::Atanh => x.atanh(),
        Unary::Sqrt => x.sqrt(),
        Unary::Exp => x.exp(),
        Unary::Ln => x.ln(),
        Unary::Log => x.log10(),
        Unary::Abs => x.abs(),
        Unary::Floor => x.floor(),
        Unary::Ceil => x.ceil(),
        Unary::Int => x.trunc(),
        Unary::Radians => x.to_radians(),
        Unary::Degrees => x.to_degrees(),
    }
}

/// Two operands' operation; comparisons and logic give 1 or 0.
pub fn binary(b: Binary, x: f64, y: f64) -> f64 {
    match b {
        Binary::Add => x + y,
        Binary::Sub => x - y,
        Binary::Mul => x * y,
        Binary::Div => x / y,
        Binary::Lt => truth(x < y),
        Binary::Le => truth(x <= y),
        Binary::Gt => truth(x > y),
        Binary::Ge => truth(x >= y),
        Binary::Eq => truth((x - y).abs() < EQUAL_WITHIN),
        Binary::Ne => truth((x - y).abs() >= EQUAL_WITHIN || x.is_nan() || y.is_nan()),
        Binary::And => truth(x != 0.0 && y != 0.0),
        Binary::Or => truth(x != 0.0 || y != 0.0),
        Binary::Atan2 => x.atan2(y),
        Binary::Pow => x.powf(y),
        Binary::Mod => x % y,
        Binary::IntDiv => (x / y).trunc(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn f(params: usize, slots: usize, code: Vec<Op>) -> Function {
        Function::new(params, slots, code).unwrap()
    }

    #[test]
    fn runs_postfix_arithmetic_with_parameters() {
        // x * x + y * 2
        let g = f(
            2,
            2,
            vec![
                Op::Load(0),
                Op::Load(0),
                Op::Binary(Binary::Mul),
                Op::Load(1),
                Op::Const(2.0),
                Op::Binary(Binary::Mul),
                Op::Binary(Binary::Add),
            ],
        );
        assert_eq!(g.eval(&[3.0, 4.0]), 17.0);
        // Missing arguments read as 0.
        assert_eq!(g.eval(&[3.0]), 9.0);
    }

    #[test]
    fn stores_slots_select_and_min_max() {
        // slot1 = x + 1; select(slot1 - 2, min(slot1, 5, 7), max(slot1, -1))
        let g = f(
            1,
            2,
            vec![
                Op::Load(0),
                Op::Const(1.0),
                Op::Binary(Binary::Add),
                Op::Store(1),
                Op::Load(1),
                Op::Const(2.0),
                Op::Binary(Binary::Sub),
                Op::Load(1),
                Op::Const(5.0),
                Op::Const(7.0),
                Op::Min(3),
                Op::Load(1),
                Op::Const(-1.0),
                Op::Max(2),
                Op::Select3,
            ],
        );
        assert_eq!(g.eval(&[0.0]), 1.0);
        assert_eq!(g.eval(&[10.0]), 11.0);
        let s4 = |a: f64| {
            f(
                0,
                0,
                vec![
                    Op::Const(a),
                    Op::Const(1.0),
                    Op::Const(2.0),
                    Op::Const(3.0),
                    Op::Select4,
                ],
            )
            .eval(&[])
        };
        assert_eq!((s4(-1.0), s4(0.0), s4(1.0)), (1.0, 2.0, 3.0));
    }

    #[test]
    fn malformed_programs_are_refused_not_run() {
        assert!(matches!(
            Function::new(0, 0, vec![Op::Binary(Binary::Add)]),
            Err(FunctionError::Malformed(_))
        ));
        assert!(Function::new(1, 1, vec![Op::Load(1)]).is_err());
        assert!(Function::new(0, 0, vec![Op::Const(1.0), Op::Const(2.0)]).is_err());
        assert!(Function::new(0, 0, vec![]).is_err());
        assert!(Function::new(0, 0, vec![Op::Const(1.0), Op::Min(0)]).is_err());
        assert!(Function::new(2, 1, vec![Op::Load(0)]).is_err());
        let big = vec![Op::Const(1.0); MAX_OPS + 1];
        assert_eq!(
            Function::new(0, 0, big),
            Err(FunctionError::TooLarge(MAX_OPS + 1))
        );
    }

    #[test]
    fn division_by_zero_and_domain_errors_give_ieee_values() {
        let div = f(
            2,
            2,
            vec![Op::Load(0), Op::Load(1), Op::Binary(Binary::Div)],
        );
        assert_eq!(div.eval(&[1.0, 0.0]), f64::INFINITY);
        assert!(div.eval(&[0.0, 0.0]).is_nan());
        assert!(div.eval(&[f64::NAN, 1.0]).is_nan());
        assert!(unary(Unary::Sqrt, -1.0).is_nan());
        assert!(unary(Unary::Ln, 0.0).is_infinite());
        assert!(binary(Binary::Mod, 1.0, 0.0).is_nan());
        assert_eq!(binary(Binary::Ne, f64::NAN, 1.0), 1.0);
        assert_eq!(binary(Binary::Eq, f64::NAN, f64::NAN), 0.0);
    }

    #[test]
    fn deep_stacks_run_on_the_heap() {
        // 1 + (1 + (1 + ...)): a stack of 100 entries, more than SMALL.
        let mut code = vec![Op::Const(1.0); 100];
        code.extend(std::iter::repeat_n(Op::Binary(Binary::Add), 99));
        assert_eq!(f(0, 0, code).eval(&[]), 100.0);
    }
}
