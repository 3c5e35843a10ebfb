//! Loading: a scene file or text read, parsed and evaluated on a thread of its own with a
//! large stack (deep nesting), cancelled from outside within a grace period.

use super::*;

/// Reads (from [`EvalOptions::world`]), parses and evaluates a scene file. `Err` only when the
/// file itself cannot be read (missing, not a regular file, larger than
/// [`crate::files::MAX_SOURCE_BYTES`], not UTF-8).
pub fn load_file(path: &Path, options: &EvalOptions) -> Result<Loaded, crate::files::FileError> {
    let text = crate::world::read_text(&*options.world, path, crate::files::MAX_SOURCE_BYTES)?;
    Ok(load_source_at(
        path,
        &path.display().to_string(),
        text,
        options,
    ))
}

/// Parses and evaluates scene text. `name` is shown in diagnostics; includes resolve relative to
/// the current directory.
pub fn load_source(name: &str, text: &str, options: &EvalOptions) -> Loaded {
    load_source_at(Path::new(name), name, text.to_string(), options)
}

fn load_source_at(path: &Path, name: &str, text: String, options: &EvalOptions) -> Loaded {
    load_with_stacks(path, name, text, options, &EVAL_STACKS)
}

/// Evaluates on a thread of the first stack size in `stacks` that can be reserved: deep but
/// bounded recursion, each stack holding [`nesting_limit`] levels.
pub(super) fn load_with_stacks(
    path: &Path,
    name: &str,
    text: String,
    options: &EvalOptions,
    stacks: &[usize],
) -> Loaded {
    let (owned_path, name, owned_options) = (path.to_path_buf(), name.to_string(), options.clone());
    // One copy of the text, shared with the source map (a large scene's text is megabytes).
    let text: std::sync::Arc<str> = text.into();
    let work = move |stack| run(&owned_path, &name, text.clone(), &owned_options, stack);
    on_eval_thread(path, stacks, &options.cancel, std::sync::Arc::new(work))
}

/// Returns the memory the evaluation thread freed (the syntax tree, pest's token lists) to the
/// system. glibc keeps a thread's freed memory in that thread's own arena, where the caller's
/// thread never reuses it: the next stage (prepare) then added its own peak on top, about 150 MB
/// more for a scene of 100 000 objects.
fn give_back_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        unsafe extern "C" {
            fn malloc_trim(pad: usize) -> std::ffi::c_int;
        }
        // SAFETY: glibc's `malloc_trim` only releases free memory; it takes no pointers.
        unsafe {
            malloc_trim(0);
        }
    }
}

/// How long a cancelled load may take to return by itself before it is left to finish alone.
const CANCEL_GRACE: std::time::Duration = std::time::Duration::from_millis(250);

/// Runs `work` (given the stack size) on a thread of the first stack in `stacks` that can be
/// made. A panic in `work` becomes an internal-error diagnostic; no stack at all, an
/// environment error. Once `cancel` is raised the caller gets "interrupted" within
/// [`CANCEL_GRACE`] even where the work cannot stop midway (parsing a large file): the thread
/// then finishes by itself, its result dropped.
pub(super) fn on_eval_thread(
    path: &Path,
    stacks: &[usize],
    cancel: &crate::cancel::Cancel,
    work: std::sync::Arc<dyn Fn(usize) -> Loaded + Send + Sync>,
) -> Loaded {
    use std::sync::mpsc::RecvTimeoutError;
    let failed = |d: Diagnostic, environment: bool, interrupted: bool| Loaded {
        scene: None,
        diagnostics: vec![d],
        sources: SourceMap::new(),
        dependencies: vec![path.to_path_buf()],
        environment,
        interrupted,
        animated: false,
        globals: Vec::new(),
    };
    let mut last_error = None;
    for &stack in stacks {
        let (done, finished) = std::sync::mpsc::channel::<()>();
        let w = work.clone();
        let spawned = std::thread::Builder::new()
            .name("sppm-eval".into())
            .stack_size(stack)
            .spawn(move || {
                let loaded = w(stack);
                give_back_freed_memory();
                let _ = done.send(());
                loaded
            });
        let handle = match spawned {
            Ok(h) => h,
            Err(e) => {
                last_error = Some(e);
                continue;
            }
        };
        // Finished (or panicked: the sender is dropped), or cancelled and not back in time.
        loop {
            match finished.recv_timeout(std::time::Duration::from_millis(50)) {
                Ok(()) | Err(RecvTimeoutError::Disconnected) => break,
                Err(RecvTimeoutError::Timeout) if cancel.is_cancelled() => {
                    if finished.recv_timeout(CANCEL_GRACE).is_err() && !handle.is_finished() {
                        return failed(Diagnostic::interrupted(), false, true);
                    }
                    break;
                }
                Err(RecvTimeoutError::Timeout) => {}
            }
        }
        match handle.join() {
            Ok(loaded) => return loaded,
            Err(panic) => {
                let what = panic
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| panic.downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "no message".into());
                return failed(
                    Diagnostic::error(
                        Span::detached(),
                        format!("internal error: the evaluation panicked ({what})"),
                    )
                    .with_help(
                        "this is a bug in sppm-lang, not in the scene; please report it with \
                         the scene that shows it",
                    ),
                    false,
                    false,
                );
            }
        }
    }
    let smallest = stacks.iter().copied().min().unwrap_or(0);
    let why = last_error.map_or_else(|| "no stack size to try".to_string(), |e| e.to_string());
    failed(
        Diagnostic::error(
            Span::detached(),
            format!(
                "cannot start the evaluation: no thread with a stack of {} could be made ({why})",
                stack_words(smallest)
            ),
        )
        .with_help(format!(
            "raise the address-space limit (`ulimit -v`, `prlimit --as`) or the thread limit: \
             evaluating needs {} of address space for its stack ({} for the deepest nesting), \
             besides the rest of the program (and, for `render`, a stack per thread of \
             `--threads`)",
            stack_words(smallest),
            stack_words(EVAL_STACK)
        )),
        true,
        false,
    )
}

fn run(
    path: &Path,
    name: &str,
    text: std::sync::Arc<str>,
    options: &EvalOptions,
    stack: usize,
) -> Loaded {
    let mut ev = Evaluator::new(options.clone());
    ev.stack = stack;
    ev.source_bytes = text.len() as u64;
    let file = ev.sources.add(path, name.to_string(), text.clone());
    ev.main_file = Some(file);
    ev.dependencies.push(path.to_path_buf());
    let canon = ev.options.world.canonical(path);
    ev.include_stack.push(canon);
    // Parsing cannot stop midway: the cancel is checked before it and at the first step after.
    if !ev.interrupted() {
        match ev.parse_within_memory(file, &text, None) {
            Ok(mut items) => {
                let mut top = TopSink::default();
                ev.run_top(&mut items, &mut top);
            }
            Err(d) => ev.errors.extend(d),
        }
    }
    // Before the unused-name warnings, which take the globals.
    let mut globals: Vec<(String, String)> = ev
        .globals
        .iter()
        .map(|(name, b)| (name.clone(), shown(&b.value)))
        .collect();
    globals.sort();
    ev.finish_warnings();
    let interrupted = ev.interrupted;
    if interrupted {
        ev.errors.push(Diagnostic::interrupted());
    }
    let has_errors = ev.errors.iter().any(Diagnostic::is_error);
    let mut diagnostics = ev.errors;
    diagnostics.extend(ev.warnings);
    let mut seen = std::collections::HashSet::new();
    ev.dependencies.retain(|p| seen.insert(p.clone()));
    Loaded {
        globals,
        dependencies: ev.dependencies,
        scene: (!has_errors).then_some(ev.scene),
        diagnostics,
        sources: ev.sources,
        environment: false,
        interrupted,
        animated: ev.animated,
    }
}

/// A value as [`Loaded::globals`] holds it: as a message shows it, cut to 200 bytes, or its type.
/// A string is cut before it is copied: a scene's strings may be hundreds of MiB, and the copy
/// would count against nothing.
fn shown(v: &Value) -> String {
    fn cut(text: &str) -> (&str, bool) {
        let mut end = 200.min(text.len());
        while !text.is_char_boundary(end) {
            end -= 1;
        }
        (&text[..end], end < text.len())
    }
    match v {
        Value::Str(s) => {
            let (head, more) = cut(s);
            format!("\"{head}{}\"", if more { "…" } else { "" })
        }
        _ => match v.show() {
            Some(text) => {
                let (head, more) = cut(&text);
                format!("{head}{}", if more { "…" } else { "" })
            }
            None => v.type_name().to_string(),
        },
    }
}
