//! Evaluation budgets: work that each loop or recursion limit allows on its own but that would
//! run for hours or exhaust memory in all ends with one spanned error, quickly.

use sppm_lang::EvalOptions;
use sppm_lang::internals::eval::{Loaded, load_source};

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

/// Each operation of an expression and each clause tested counts: a 5 000-term sum, or a
/// `#switch` of 20 000 clauses, evaluated in a loop once took one step per iteration, so a
/// budget of 50 million steps allowed hours (1.3 ms per iteration of the sum).
#[test]
fn long_expressions_and_clause_chains_count_by_their_length() {
    let opts = EvalOptions {
        max_steps: 1_000_000,
        ..EvalOptions::default()
    };
    let sum = format!(
        "#for (I, 1, 1000)\n #declare X = I{};\n#end\n",
        " + I".repeat(4999)
    );
    let cases = format!(
        "#for (I, 1, 1000)\n #switch (-1)\n{} #end\n#end\n",
        " #case (1)\n".repeat(2000)
    );
    let elifs = format!(
        "#for (I, 1, 1000)\n #if (false)\n{} #end\n#end\n",
        " #elif (false)\n".repeat(2000)
    );
    for text in [sum, cases, elifs] {
        let l = load(&text, &opts);
        assert_eq!(
            errors(&l),
            ["the evaluation took more than 1000000 steps"],
            "{}",
            &text[..60]
        );
    }
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
        ["blocks, directive bodies and macro calls nested deeper than 100000"],
        "{e:?}"
    );
}

/// A macro whose body nests `ifs` `#if`s around its recursive call, called with depth `n`.
fn nested_ifs(ifs: usize, n: usize) -> String {
    format!(
        "#macro M(N)\n{}#if (N > 0) M(N - 1) #end\n{}#end\nM({n})\nsphere {{ <0,0,0>, 1 }}\n",
        "#if (1) ".repeat(ifs),
        "#end ".repeat(ifs)
    )
}

#[test]
fn deep_directive_nesting_in_recursion_is_an_error_not_a_stack_overflow() {
    // 11 directive bodies per call: 99 000 calls are 1.1 million levels.
    let opts = EvalOptions {
        max_depth: 100_000,
        ..EvalOptions::default()
    };
    let e = errors(&load(&nested_ifs(10, 99_000), &opts));
    assert_eq!(
        e,
        ["blocks, directive bodies and macro calls nested deeper than 100000"],
        "{e:?}"
    );
    // Just within the bound (196 levels per call, 500 calls: 98 500 levels) the evaluation
    // thread's stack holds them.
    let l = load(&nested_ifs(195, 500), &opts);
    assert!(errors(&l).is_empty(), "{:?}", errors(&l));
}

/// The budget counts the work a step does on large values, not only the steps: a string of
/// 1 MiB joined, compared or measured in a loop, an array of 4 000 numbers made in a loop, a
/// macro of 5 000 arguments called in a loop, and strings of 1 MiB gathered into an array (the
/// memory a loop holds) each run out of a 10^7-step budget within a few hundred iterations,
/// where counting statements alone would have let each loop run its million iterations
/// (hours, or tens of gigabytes).
#[test]
fn work_on_large_values_counts_against_the_budget() {
    let opts = EvalOptions {
        max_steps: 10_000_000,
        ..EvalOptions::default()
    };
    let big = "#declare S = \"0123456789abcdef\";\n#for (I, 1, 16) #declare S = S + S; #end\n";
    let args = vec!["1"; 5000].join(", ");
    let params: Vec<String> = (0..5000).map(|i| format!("P{i}")).collect();
    let cases = [
        format!("{big}#for (I, 1, 1000000) #declare U = S + \"x\"; #end\n"),
        format!("{big}#declare T = S;\n#for (I, 1, 1000000) #if (S == T) #end #end\n"),
        format!("{big}#for (I, 1, 1000000) #declare N = len(S); #end\n"),
        format!(
            "#for (I, 1, 1000000) #declare A = [{}]; #end\n",
            vec!["I"; 4000].join(", ")
        ),
        format!(
            "#macro M({})\n#end\n#for (I, 1, 1000000) M({args}) #end\n",
            params.join(", ")
        ),
        format!("{big}#declare L = [0];\n#for (I, 1, 1000000) #declare L = [S + \"x\", L]; #end\n"),
    ];
    for text in &cases {
        let l = load(text, &opts);
        let e = errors(&l);
        assert_eq!(
            e,
            ["the evaluation took more than 10000000 steps"],
            "{e:?} for {}",
            &text[text.len().saturating_sub(80)..]
        );
    }
}

/// Under a memory limit, an image whose decoded pixels (with the images loaded before) would
/// not fit in it is refused from its header, at the image's name, before it is decoded: a
/// scene's images once decoded up to the fixed cap of 2^27 pixels (1.5 GiB) whatever
/// `--memory-limit` said, and only then did the render's estimate refuse them.
#[test]
fn images_beyond_the_memory_limit_are_refused_before_they_are_decoded() {
    let dir = tempfile::tempdir().unwrap();
    // 1024 x 1024 pixels: 12 MiB decoded.
    image::RgbImage::from_pixel(1024, 1024, image::Rgb([200, 100, 50]))
        .save(dir.path().join("a.png"))
        .unwrap();
    let scene = dir.path().join("s.scn");
    std::fs::write(
        &scene,
        "quad { <0, 0, 0>, <1, 0, 0>, <0, 1, 0> material { diffuse texture { image \"a.png\" } } }\n\
         quad { <0, 0, 1>, <1, 0, 0>, <0, 1, 0> material { diffuse texture { image \"a.png\" linear } } }\n",
    )
    .unwrap();
    let with = |limit: Option<u64>| {
        let options = EvalOptions {
            memory_limit: limit,
            ..EvalOptions::default()
        };
        sppm_lang::internals::eval::load_file(&scene, &options).unwrap()
    };
    // Without a limit, and with room for both (24 MiB): loaded.
    for limit in [None, Some(25 << 20)] {
        let l = with(limit);
        assert!(errors(&l).is_empty(), "{limit:?}: {:?}", errors(&l));
    }
    // Room for one: the second (the same file read as linear data) is refused at its name.
    let l = with(Some(20 << 20));
    let e = errors(&l);
    assert_eq!(e.len(), 1, "{e:?}");
    assert!(
        e[0].contains("1024x1024") && e[0].contains("memory limit of 20.0 MiB"),
        "{e:?}"
    );
    let d = error_naming_the_memory_limit(&l);
    let text = std::fs::read_to_string(&scene).unwrap();
    let at = d.span.start as usize;
    assert_eq!(
        text[..at].matches("a.png").count(),
        1,
        "the error is not at the second image's name: {:?}",
        d.span
    );
    // Room for none.
    let e = errors(&with(Some(4 << 20)));
    assert!(
        !e.is_empty() && e.iter().all(|m| m.contains("memory limit")),
        "{e:?}"
    );
}

/// A typo in a macro called on 100 000 lines is shown once, and the evaluation stops after
/// `MAX_ERRORS` errors with a note at the first statement it did not evaluate.
#[test]
fn an_error_repeated_by_many_calls_is_shown_once_and_the_count_is_bounded() {
    let mut text = String::from("#macro M() sphere { <0, 0, 0>, Radus } #end\n");
    for _ in 0..100_000 {
        text.push_str("M()\n");
    }
    let l = load(&text, &EvalOptions::default());
    assert_eq!(errors(&l), ["unknown identifier `Radus`"]);
    let notes: Vec<&str> = l
        .diagnostics
        .iter()
        .filter(|d| !d.is_error())
        .map(|d| d.message.as_str())
        .collect();
    let last = format!(
        "more than {} errors: the evaluation stopped",
        sppm_lang::internals::eval::MAX_ERRORS
    );
    assert_eq!(notes, [last.as_str()]);
    let note = l.diagnostics.iter().find(|d| !d.is_error()).unwrap();
    // At the call after the 100th.
    assert_eq!(
        l.sources.line_col(note.span).0,
        sppm_lang::internals::eval::MAX_ERRORS + 2
    );
}

/// Each unknown name's "did you mean" reads every declared name: with 50 000 of them and 5 000
/// lines of unknown names, the errors stop at `MAX_ERRORS` and only the first few are searched.
#[test]
fn many_unknown_names_among_many_declarations_are_reported_quickly() {
    let mut text = String::new();
    for i in 0..50_000 {
        text.push_str(&format!("#declare Name{i} = {i};\n"));
    }
    for i in 0..5_000 {
        text.push_str(&format!("sphere {{ <0, 0, 0>, Nmae{i} }}\n"));
    }
    let start = std::time::Instant::now();
    let l = load(&text, &EvalOptions::default());
    assert!(start.elapsed().as_secs() < 20, "took {:?}", start.elapsed());
    let e = errors(&l);
    assert_eq!(e.len(), sppm_lang::internals::eval::MAX_ERRORS);
    assert_eq!(e[0], "unknown identifier `Nmae0`");
    // The first unknown names get their nearest declared name, the later ones the plain help.
    let helps: Vec<&str> = l
        .diagnostics
        .iter()
        .filter(|d| d.is_error())
        .map(|d| d.help.as_deref().unwrap_or(""))
        .collect();
    assert_eq!(helps[0], "did you mean `Name0`?");
    assert_eq!(helps[99], "declare it first: `#declare Nmae99 = ...`");
}

/// A scene file or include whose text would take more memory to parse than the memory limit
/// allows (`syntax::parse_memory`: its lexemes times the most the parser was measured to take
/// per lexeme) is refused before it is parsed, at the `#include` or the file's start, with a
/// help naming `--memory-limit`: a 40 MB array literal once took the parser past 5 GB and
/// aborted the process under a 4 GB address-space cap.
#[test]
fn text_too_large_to_parse_within_the_memory_limit_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    // 64 KiB of text, 65 544 lexemes: 20.0 MiB to parse at 320 bytes each.
    let big = format!("#declare A = [{}1];\n", "1,".repeat(32 * 1024));
    let need = sppm_lang::internals::syntax::parse_memory(&big);
    assert_eq!(
        need,
        65_544 * sppm_lang::internals::syntax::PARSE_BYTES_PER_LEXEME
    );
    std::fs::write(dir.path().join("big.scn"), &big).unwrap();
    let main = dir.path().join("main.scn");
    let main_text = "#include \"big.scn\"\n";
    std::fs::write(&main, main_text).unwrap();
    // The load holds the scene file's parse too: one total for every file it reads.
    let both = need + sppm_lang::internals::syntax::parse_memory(main_text);
    let with = |path: &std::path::Path, limit: Option<u64>| {
        let options = EvalOptions {
            memory_limit: limit,
            ..EvalOptions::default()
        };
        sppm_lang::internals::eval::load_file(path, &options).unwrap()
    };
    // Room to parse both (and no limit given: the default of 2 GiB): loaded.
    for limit in [None, Some(both)] {
        let l = with(&main, limit);
        assert!(errors(&l).is_empty(), "{limit:?}: {:?}", errors(&l));
    }
    // Room for the included file alone, but not with the scene's own: refused at the include.
    let e = errors(&with(&main, Some(both - 1)));
    assert!(
        e.len() == 1 && e[0].contains("the load holds") && e[0].contains("parsed text"),
        "{e:?}"
    );
    // Not enough: refused at the include, and as the scene file itself at its start.
    for (path, at) in [(&main, "#include ".len()), (&dir.path().join("big.scn"), 0)] {
        let l = with(path, Some(19 << 20));
        let e = errors(&l);
        assert_eq!(e.len(), 1, "{e:?}");
        assert!(
            e[0].contains("too large to parse within the memory limit")
                && e[0].contains("20.0 MiB")
                && e[0].contains("19.0 MiB"),
            "{e:?}"
        );
        let d = error_naming_the_memory_limit(&l);
        assert_eq!(d.span.start as usize, at, "{:?}", d.span);
    }
}

/// The load's first error, whose help must name `--memory-limit`.
fn error_naming_the_memory_limit(l: &Loaded) -> &sppm_lang::Diagnostic {
    let d = l.diagnostics.iter().find(|d| d.is_error()).unwrap();
    assert!(
        d.help
            .as_deref()
            .is_some_and(|h| h.contains("--memory-limit")),
        "{:?}",
        d.help
    );
    d
}

/// A diagnostic keeps at most `MAX_DIAGNOSTIC_TEXT` bytes of its message, labels and help, with
/// a note of how much it left out: 999 `#debug` messages of a 16 MiB string once held 16 GB
/// (the load was killed at 2 GB), and an image named by such a string put it into its error.
#[test]
fn diagnostics_keep_a_bounded_part_of_long_strings() {
    let max = sppm_lang::internals::diag::MAX_DIAGNOSTIC_TEXT;
    let l = load(
        "#declare S = \"ab\";\n#for (I, 1, 20) #declare S = S + S; #end\n\
         #for (I, 1, 50) #debug S #end\n\
         sphere { <0, 0, 0>, 1 material { diffuse texture { image S } } }\n",
        &EvalOptions::default(),
    );
    let notes: Vec<_> = l
        .diagnostics
        .iter()
        .filter(|d| d.severity == sppm_lang::Severity::Note)
        .collect();
    assert_eq!(notes.len(), 50);
    for d in &notes {
        assert!(
            d.message.len() <= max && d.message.ends_with("MiB more not shown)"),
            "{} bytes: {}",
            d.message.len(),
            &d.message[d.message.len().saturating_sub(60)..]
        );
    }
    let e = l
        .diagnostics
        .iter()
        .find(|d| d.is_error())
        .expect("the image error");
    for text in [&e.message, &e.label]
        .into_iter()
        .chain(e.help.as_ref())
        .chain(e.labels.iter().map(|(_, l)| l))
    {
        assert!(text.len() <= max, "{} bytes", text.len());
    }
}

/// A load keeps at most `MAX_WARNINGS` warnings and then says the rest were left out: 665 000
/// "empty union" warnings of a 4.7 MB generated file once held 2.75 GB and printed 2.3 GB.
#[test]
fn warnings_are_bounded() {
    let text = format!(
        "{}sphere {{ <0, 0, 0>, 1 }}\n",
        "union { }\n".repeat(sppm_lang::internals::eval::MAX_WARNINGS + 500)
    );
    let l = load(&text, &EvalOptions::default());
    assert!(errors(&l).is_empty(), "{:?}", errors(&l));
    assert_eq!(
        l.diagnostics.len(),
        sppm_lang::internals::eval::MAX_WARNINGS + 1
    );
    let last = l.diagnostics.last().unwrap();
    assert!(
        last.message.contains("warnings: the rest are not shown"),
        "{}",
        last.message
    );
}
