//! Evaluation budgets: work that each loop or recursion limit allows on its own but that would
//! run for hours or exhaust memory in all ends with one spanned error, quickly.

use sppm_lang::{EvalOptions, Loaded, load_source};

fn errors(l: &Loaded) -> Vec<String> {
    l.diagnostics
        .iter()
        .filter(|d| d.is_error())
        .map(|d| d.message.clone())
        .collect()
}

fn load(text: &str, options: &EvalOptions) -> Loaded {
    let start = std::time::Instant::now();
    let l = load_source("budget.scn", text, options);
    assert!(start.elapsed().as_secs() < 60, "took {:?}", start.elapsed());
    l
}

#[test]
fn exponential_recursion_runs_out_of_steps() {
    let opts = EvalOptions {
        max_steps: 100_000,
        ..EvalOptions::default()
    };
    let l = load(
        "#macro F(N)\n #if (N > 0)\n  F(N-1) F(N-1)\n #end\n#end\nF(60)\n",
        &opts,
    );
    let e = errors(&l);
    assert_eq!(e, ["the evaluation took more than 100000 steps"], "{e:?}");
    assert!(l.scene.is_none());
    assert!(!l.diagnostics[0].span.is_detached());
}

#[test]
fn nested_loops_each_under_their_limit_run_out_of_steps() {
    let opts = EvalOptions {
        max_steps: 1_000_000,
        ..EvalOptions::default()
    };
    let l = load(
        "#declare S = 0;\n#for (I, 1, 999999)\n #for (J, 1, 999999)\n  #declare S = S + 1;\n #end\n#end\n",
        &opts,
    );
    assert_eq!(errors(&l), ["the evaluation took more than 1000000 steps"]);
}

#[test]
fn empty_loop_bodies_count_too() {
    let opts = EvalOptions {
        max_steps: 10_000,
        ..EvalOptions::default()
    };
    let l = load(
        "#for (I, 1, 999999)\n #for (J, 1, 999999)\n #end\n#end\n",
        &opts,
    );
    assert_eq!(errors(&l), ["the evaluation took more than 10000 steps"]);
}

#[test]
fn a_union_copied_into_itself_stops_at_the_part_limit() {
    let opts = EvalOptions {
        max_objects: 10_000,
        ..EvalOptions::default()
    };
    let l = load(
        "#declare U = sphere { <0,0,0> 1 }\n#for (I, 1, 60)\n #declare U = union { object { U } object { U } }\n#end\n",
        &opts,
    );
    let e = errors(&l);
    assert_eq!(e.len(), 1, "{e:?}");
    assert!(
        e[0].contains("more than 10000 parts") || e[0].contains("more than 20000 parts in all"),
        "{e:?}"
    );
}

#[test]
fn strings_cannot_double_without_end() {
    let l = load(
        "#declare S = \"ab\";\n#for (I, 1, 60)\n #declare S = S + S;\n#end\n",
        &EvalOptions::default(),
    );
    let e = errors(&l);
    assert_eq!(e.len(), 1, "{e:?}");
    assert!(
        e[0].contains("more than the limit of 16777216 bytes"),
        "{e:?}"
    );
}

#[test]
fn deep_block_nesting_in_recursion_is_an_error_not_a_stack_overflow() {
    // 60 nested blocks per macro call: 12 000 calls are 732 000 levels, far past the bound,
    // while the macro depth itself is allowed.
    let text = format!(
        "#macro F(N)\n #if (N > 0)\n {}F(N-1){}\n #else sphere {{ <0,0,0> 1 }} #end\n#end\nF(12000)\n",
        "union { ".repeat(60),
        " }".repeat(60)
    );
    let opts = EvalOptions {
        max_depth: 100_000,
        ..EvalOptions::default()
    };
    let l = load(&text, &opts);
    let e = errors(&l);
    assert_eq!(
        e,
        ["blocks and macro calls nested deeper than 100000"],
        "{e:?}"
    );
}
