use super::load::{load_with_stacks, on_eval_thread};
use super::*;

/// A stack no thread can have (beyond any address space): its spawn fails as it does
/// under a low `ulimit -v`.
const UNRESERVABLE: usize = 1 << 60;

/// A macro recursing `depth` levels (each level a macro call and an `#if` body).
fn recursion(depth: usize) -> String {
    format!(
        "#macro R(N) #if (N > 0) R(N - 1) #end #end\nR({depth})\n\
         sphere {{ <0, 0, 0>, 1 material {{ diffuse rgb 0.5 }} }}\n"
    )
}

fn load(text: &str, max_depth: usize, stacks: &[usize]) -> Loaded {
    let options = EvalOptions {
        max_depth,
        ..EvalOptions::default()
    };
    load_with_stacks(Path::new("t.scn"), "t.scn", text.into(), &options, stacks)
}

#[test]
fn a_smaller_stack_is_used_when_the_largest_cannot_be_reserved() {
    let l = load(&recursion(200), 256, &[UNRESERVABLE, 1 << 26]);
    assert!(!l.has_errors(), "{:?}", l.diagnostics);
    assert!(l.scene.is_some() && !l.environment);
}

#[test]
fn a_smaller_stack_lowers_the_macro_depth_and_says_why_when_reached() {
    let limit = nesting_limit(1 << 26);
    assert!(limit < 10_000, "{limit}");
    // Under the lowered limit: no word about it.
    let l = load(&recursion(limit / 4), 100_000, &[UNRESERVABLE, 1 << 26]);
    assert!(!l.has_errors(), "{:?}", l.diagnostics);
    assert!(l.diagnostics.is_empty(), "{:?}", l.diagnostics);
    // Deeper: the error names the lowered limit and the address space.
    let l = load(&recursion(10_000), 100_000, &[UNRESERVABLE, 1 << 26]);
    assert!(l.has_errors() && !l.environment);
    let d = &l.diagnostics[0];
    assert!(!d.span.is_detached(), "{d:?}");
    assert!(d.message.contains(&limit.to_string()), "{}", d.message);
    assert!(d.message.contains("address space"), "{}", d.message);
    assert!(d.message.contains("64 MiB"), "{}", d.message);
    assert!(d.help.as_deref().unwrap().contains("ulimit -v"), "{d:?}");
    // A `--max-depth` below the lowered limit is the user's own: the usual message.
    let l = load(&recursion(10_000), 100, &[UNRESERVABLE, 1 << 26]);
    let d = &l.diagnostics[0];
    assert!(d.message.contains("deeper than 100 ("), "{}", d.message);
    assert!(!d.message.contains("address space"), "{}", d.message);
}

#[test]
fn the_full_stack_keeps_the_full_limits() {
    assert_eq!(nesting_limit(EVAL_STACK), MAX_EVAL_NESTING);
    assert_eq!(nesting_limit(1 << 28), MAX_EVAL_NESTING / 4);
    let l = load(&recursion(10_000), 100_000, &EVAL_STACKS);
    assert!(!l.has_errors(), "{:?}", l.diagnostics);
}

/// Value macros recurse through expressions (a call inside `1 + ...` inside an `#if`
/// body): filling the nesting limit of a small stack fits in it, and running past it is
/// the nesting error, not a stack overflow.
#[test]
fn value_macro_recursion_fits_the_stack_it_is_limited_to() {
    let stack = 1 << 26;
    let limit = nesting_limit(stack);
    // Each level of `Sum` is a macro call and an `#if` body: two levels of nesting.
    let sum = |depth: usize| {
        format!(
            "#macro Sum(N) #if (N <= 0) 0 #else 1 + Sum(N - 1) #end #end\n\
             sphere {{ <0, 0, 0>, Sum({depth}) }}\n"
        )
    };
    let l = load(&sum(limit / 2 - 2), 100_000, &[stack]);
    assert!(!l.has_errors(), "{:?}", l.diagnostics);
    let radius = match l.scene.unwrap().objects[0].shape {
        crate::scene::ShapeDecl::Sphere { radius, .. } => radius,
        ref s => panic!("{s:?}"),
    };
    assert_eq!(radius, (limit / 2 - 2) as f64);
    let l = load(
        "#macro Down(N) Down(N - 1) + 1 #end\n#declare T = Down(3);\n",
        100_000,
        &[stack],
    );
    let d = &l.diagnostics[0];
    assert!(d.message.contains(&limit.to_string()), "{}", d.message);
    assert!(!d.span.is_detached(), "{d:?}");
}

#[test]
fn a_panic_in_the_evaluation_is_an_internal_error() {
    let l = on_eval_thread(
        Path::new("t.scn"),
        &EVAL_STACKS,
        &Default::default(),
        std::sync::Arc::new(|_| panic!("on purpose")),
    );
    assert!(l.scene.is_none() && !l.environment);
    let d = &l.diagnostics[0];
    assert!(d.message.contains("internal error"), "{}", d.message);
    assert!(d.message.contains("on purpose"), "{}", d.message);
    assert!(d.help.is_some());
}

/// A load cancelled in the middle of a loop that would run for minutes returns within a
/// second of the cancel, with no scene and the one word "interrupted"; a load cancelled
/// before it starts does not evaluate at all.
#[test]
fn a_cancelled_load_stops_at_its_next_step() {
    let endless = "#declare I = 0;\n#while (I < 1e15) #declare I = I + 1; #end\n\
                   sphere { <0, 0, 0>, 1 }\n";
    let cancel = crate::cancel::Cancel::new();
    let options = EvalOptions {
        max_iterations: u64::MAX,
        max_steps: u64::MAX,
        cancel: cancel.clone(),
        ..EvalOptions::default()
    };
    let raised = std::thread::scope(|s| {
        let raiser = s.spawn(|| {
            std::thread::sleep(std::time::Duration::from_millis(300));
            cancel.cancel();
            std::time::Instant::now()
        });
        let l = load_source("endless.scn", endless, &options);
        let returned = std::time::Instant::now();
        let raised = raiser.join().unwrap();
        (l, returned.saturating_duration_since(raised))
    });
    let (l, after) = raised;
    println!("the load returned {after:?} after the cancel");
    assert!(after < std::time::Duration::from_secs(1), "{after:?}");
    assert!(l.interrupted && l.scene.is_none() && !l.environment);
    assert_eq!(l.diagnostics.len(), 1, "{:?}", l.diagnostics);
    assert_eq!(l.diagnostics[0].message, "interrupted");
    // Raised before the load: nothing is evaluated (a budget of one step would fail
    // otherwise, with an error of its own).
    let options = EvalOptions {
        max_steps: 1,
        ..options
    };
    let l = load_source("endless.scn", endless, &options);
    assert!(l.interrupted && l.scene.is_none());
    assert_eq!(l.diagnostics.len(), 1, "{:?}", l.diagnostics);
    // A handle nobody raised changes nothing.
    let l = load_source("t.scn", &recursion(3), &EvalOptions::default());
    assert!(!l.interrupted && l.scene.is_some(), "{:?}", l.diagnostics);
}

#[test]
fn no_stack_at_all_is_an_environment_error_with_help() {
    let l = load(&recursion(2), 256, &[UNRESERVABLE]);
    assert!(l.environment && l.scene.is_none());
    let d = &l.diagnostics[0];
    assert!(d.is_error());
    assert!(
        d.message.contains("cannot start the evaluation"),
        "{}",
        d.message
    );
    assert!(d.help.as_deref().unwrap().contains("ulimit -v"), "{d:?}");
}
