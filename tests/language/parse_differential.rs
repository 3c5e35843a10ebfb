//! A differential check of the parser: with `SPPM_PARSE_DUMP=file` set, parses the repository's
//! scenes and a few thousand deterministic mutations of them and writes, for each input, the
//! syntax tree (with spans) or the rendered syntax error. Run it before and after a parser change
//! and compare the two files:
//! `SPPM_PARSE_DUMP=/tmp/a.txt cargo test --test language parse_differential:: -- --ignored`.

use std::fmt::Write;

use sppm_lang::FileId;
use sppm_lang::internals::syntax;
use sppm_lang::{SourceMap, render_plain};

/// Tokens a mutation inserts, separated by `|`.
const TOKENS: &str = "{|}|<|>|,|(|)|[|]|#declare X = |#end|#if (1)|#switch (1)|#case (1)|#break|#debug \"a\"|=|1|-2.5|.5|1e3|rgb|x|X|sphere|material|translate|+|*|-|/|==|<=|&&|!|\"s\"|// c\n|/* c */| |\n|true|A[0]|B.x|f(1, 2)";

fn inputs() -> Vec<String> {
    let mut files = Vec::new();
    for dir in ["examples", "tests/bad", "tests/good", "tests/good/parts"] {
        let Ok(rd) = std::fs::read_dir(dir) else {
            continue;
        };
        let mut paths: Vec<_> = rd
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "scn"))
            .collect();
        paths.sort();
        for p in paths {
            files.push(std::fs::read_to_string(p).unwrap());
        }
    }
    files
}

#[test]
#[ignore = "writes a dump for a differential run; see the module doc"]
fn parse_dump() {
    let Some(out) = std::env::var_os("SPPM_PARSE_DUMP") else {
        return;
    };
    let seeds = inputs();
    let mut cases = seeds.clone();
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move |n: usize| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state % n.max(1) as u64) as usize
    };
    for _ in 0..4000 {
        let mut t: Vec<char> = seeds[next(seeds.len())].chars().collect();
        for _ in 0..1 + next(3) {
            let at = next(t.len() + 1);
            match next(3) {
                0 => {
                    let end = (at + 1 + next(8)).min(t.len());
                    t.drain(at.min(end)..end);
                }
                1 => {
                    let tokens: Vec<&str> = TOKENS.split('|').collect();
                    let tok = tokens[next(tokens.len())];
                    t.splice(at..at, tok.chars());
                }
                _ => {
                    let end = (at + 1 + next(12)).min(t.len());
                    let piece: Vec<char> = t[at.min(end)..end].to_vec();
                    let to = next(t.len() + 1);
                    t.splice(to..to, piece);
                }
            }
        }
        cases.push(t.into_iter().collect());
    }
    let mut dump = String::new();
    for (i, text) in cases.iter().enumerate() {
        let mut map = SourceMap::new();
        let id: FileId = map.add("case.scn".as_ref(), "case.scn".into(), text.clone());
        match syntax::parse(id, text) {
            Ok(items) => writeln!(dump, "#{i} ok {items:?}").unwrap(),
            Err(d) => writeln!(dump, "#{i} err\n{}", render_plain(&map, &d, 100)).unwrap(),
        }
    }
    std::fs::write(out, dump).unwrap();
}
