//! The direct reader against pest: the keyword list, generated texts, the repository's scenes.

use std::collections::BTreeSet;

use pest::Parser;

use super::*;
use crate::syntax::errors::check_nesting;
use crate::syntax::parser::{Rule, SceneParser, parse_by_item, parse_whole};

/// The words of the grammar's `kw_word` rule: each `'c'..'c'` letter followed by the
/// literals after it.
fn grammar_keywords() -> BTreeSet<String> {
    let g = include_str!("../../../grammar/scene.pest");
    let start = g.find("kw_word = _{").expect("kw_word rule");
    let rule = &g[start..start + g[start..].find("\n}\n").expect("end of kw_word")];
    let (mut words, mut letter) = (BTreeSet::new(), String::new());
    let mut rest = rule;
    while let Some(i) = rest.find(['\'', '"']) {
        let quote = rest.as_bytes()[i];
        rest = &rest[i + 1..];
        let close = rest.find(quote as char).expect("closing quote");
        let lit = &rest[..close];
        rest = &rest[close + 1..];
        if quote == b'"' {
            words.insert(format!("{letter}{lit}"));
        } else if let Some(to) = rest.strip_prefix("..'") {
            // `'a'..'f'` (a lookahead) or `'c'..'c'` (a word's first letter).
            let hi = &to[..to.find('\'').expect("range end")];
            if hi == lit {
                letter = lit.to_string();
            }
            rest = &to[hi.len() + 1..];
        }
    }
    words
}

fn pest_keyword(word: &str) -> bool {
    SceneParser::parse(Rule::keyword, word)
        .is_ok_and(|mut p| p.next().is_some_and(|k| k.as_str() == word))
}

#[test]
fn keywords_are_the_grammars() {
    let ours: BTreeSet<String> = KEYWORDS.iter().map(|w| w.to_string()).collect();
    assert_eq!(ours.len(), KEYWORDS.len(), "a keyword listed twice");
    assert!(KEYWORDS.is_sorted(), "binary search needs the list sorted");
    assert_eq!(ours, grammar_keywords());
    for w in KEYWORDS {
        assert!(pest_keyword(w), "{w}");
        assert!(SceneParser::parse(Rule::ident, w).is_err(), "{w}");
        // Words next to a keyword: longer, shorter, with a capital.
        for near in [
            format!("{w}2"),
            format!("{w}_"),
            w[..w.len() - 1].to_string(),
        ] {
            assert_eq!(pest_keyword(&near), is_keyword(&near), "{near}");
        }
        assert!(!pest_keyword(&w.to_uppercase()));
    }
}

/// A deterministic stream of choices.
struct Choices(u64);

impl Choices {
    fn next(&mut self, n: usize) -> usize {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 % n as u64) as usize
    }

    fn pick<'a>(&mut self, options: &[&'a str]) -> &'a str {
        options[self.next(options.len())]
    }
}

const BLANKS: &[&str] = &[
    "",
    " ",
    " ",
    "  ",
    "\n",
    "\t",
    "\r\n",
    "\u{0B}",
    "\u{0C}",
    "// c\n",
    "/* c */",
    "/* a /* b */ c */",
    "/*/ x */",
    "//",
];
const OPS: &[&str] = &[
    "+", "-", "*", "/", "<", "<=", ">", ">=", "==", "!=", "&&", "&", "||", "|", "=", "!", "?", ":",
];
const WORDS: &[&str] = &[
    "x",
    "X",
    "A_1",
    "_",
    "scale2",
    "rgbx",
    "true",
    "false",
    "linear_",
    "sphere",
    "material",
    "seed",
    "translate",
    "radius",
    "color_map",
    "function",
    "rgb",
    "rgbft",
    "é",
    "f",
];
const NUMBERS: &[&str] = &[
    "1", "0.5", ".5", "1.", "2e3", "1e", "3E-2", "12", "1.e2", "0",
];

fn operand(c: &mut Choices, depth: usize, out: &mut String) {
    let leaf = depth == 0;
    match c.next(if leaf { 3 } else { 9 }) {
        0 => out.push_str(c.pick(NUMBERS)),
        1 => out.push_str(c.pick(WORDS)),
        2 => out.push_str(c.pick(&["-", "+", "!", "rgb ", "rgbf", "-rgb "])),
        3 => {
            out.push('<');
            for i in 0..1 + c.next(4) {
                if i > 0 {
                    out.push_str(c.pick(&[",", ", ", " ", ",,", ""]));
                }
                expr(c, depth - 1, out);
            }
            out.push_str(c.pick(&[">", ",>", " >", "", ", >"]));
        }
        4 => {
            out.push('(');
            expr(c, depth - 1, out);
            out.push_str(c.pick(&[")", " )", ""]));
        }
        5 => {
            out.push_str(c.pick(WORDS));
            out.push_str(c.pick(BLANKS));
            out.push('{');
            items(c, depth - 1, out);
            out.push_str(c.pick(&["}", " }", ""]));
        }
        6 => {
            out.push_str(c.pick(WORDS));
            out.push_str(c.pick(&["(", " (", "( "]));
            for i in 0..c.next(3) {
                if i > 0 {
                    out.push_str(c.pick(&[",", ", ", ""]));
                }
                expr(c, depth - 1, out);
            }
            out.push_str(c.pick(&[")", ",)", ""]));
        }
        7 => {
            operand(c, depth - 1, out);
            out.push_str(c.pick(BLANKS));
            out.push_str(c.pick(&[".x", ". y", ".", ".5", "[1]", "[ x + 1 ]", "["]));
        }
        _ => out.push_str(c.pick(&["\"s\"", "[1, 2]", "A.rgb", "-(1)"])),
    }
}

fn expr(c: &mut Choices, depth: usize, out: &mut String) {
    operand(c, depth, out);
    for _ in 0..c.next(4) {
        out.push_str(c.pick(BLANKS));
        // Mostly operators that join (so that precedence is tested), sometimes any.
        if c.next(4) == 0 {
            out.push_str(c.pick(OPS));
        } else {
            out.push_str(c.pick(&OPS[..14]));
        }
        out.push_str(c.pick(BLANKS));
        operand(c, depth, out);
    }
}

fn items(c: &mut Choices, depth: usize, out: &mut String) {
    for _ in 0..c.next(5) {
        out.push_str(c.pick(BLANKS));
        match c.next(6) {
            0 => out.push(','),
            1 => out.push_str(c.pick(&["translate", "radius", "linear", "scale", "seed"])),
            2 => {
                out.push_str(c.pick(&["#declare", "#local", "#declareX", "# declare"]));
                out.push_str(c.pick(&[" A", " x", "  rgb", " radius", "B"]));
                out.push_str(c.pick(&[" = ", "=", " "]));
                expr(c, depth, out);
                out.push_str(c.pick(&["", ";", " ;", " "]));
            }
            3 => out.push_str(c.pick(&["#if (1) #end", "}", "#", "\"s\"", "[0 1]", "@"])),
            _ => expr(c, depth, out),
        }
    }
    out.push_str(c.pick(BLANKS));
}

/// Whether the direct reader reads every item of `text` by itself.
fn read_alone(text: &str) -> bool {
    let mut r = Reader::new(FileId(2), text, 0);
    while r.blanks().is_some() {
        if r.pos == text.len() {
            return true;
        }
        if r.item().is_none() {
            return false;
        }
    }
    false
}

/// The item-by-item parse (the direct reader, pest for the rest) gives the whole-file
/// parse's tree (spans included) or errors, and no tree where the whole file has a syntax
/// error. Returns whether it gave a tree.
fn same_as_pest(text: &str) -> bool {
    let Ok(stray) = check_nesting(FileId(2), text) else {
        return false;
    };
    let whole = format!("{:?}", parse_whole(FileId(2), text, stray));
    match parse_by_item(FileId(2), text) {
        Some(by_item) => {
            assert_eq!(format!("{by_item:?}"), whole, "{text:?}");
            true
        }
        None => {
            assert!(whole.starts_with("Err("), "{text:?}: {whole}");
            false
        }
    }
}

/// Generated texts, valid and not.
#[test]
fn the_reader_builds_the_grammars_tree() {
    let mut c = Choices(0x2545_f491_4f6c_dd1d);
    let (mut parsed, mut alone, cases) = (0, 0, 6000);
    for _ in 0..cases {
        let mut text = String::new();
        items(&mut c, 3, &mut text);
        parsed += usize::from(same_as_pest(&text));
        alone += usize::from(read_alone(&text));
    }
    // Trees and errors both occur often enough to mean something, and the reader reads
    // whole files by itself in many of the cases that parse.
    assert!(
        parsed > cases / 10 && parsed < cases * 9 / 10,
        "{parsed} of {cases}"
    );
    assert!(alone > parsed / 4, "{alone} of {parsed}");
}

/// The repository's scenes, and the same with a character deleted or a token inserted at
/// deterministic places.
#[test]
fn the_reader_reads_the_repositorys_scenes_as_pest_does() {
    let root = crate::repo_root();
    let mut texts = Vec::new();
    for dir in ["examples", "tests/good", "tests/good/parts", "tests/bad"] {
        let Ok(entries) = std::fs::read_dir(root.join(dir)) else {
            continue;
        };
        let mut paths: Vec<_> = entries.map(|e| e.expect("entry").path()).collect();
        paths.sort();
        for p in paths {
            if p.extension().is_some_and(|e| e == "scn") {
                texts.push(std::fs::read_to_string(&p).expect("scene text"));
            }
        }
    }
    assert!(texts.len() > 100, "{} scenes", texts.len());
    let tokens = [
        "<", ">", ",", "{", "}", "(", ")", "-", ".", "/*", "#", "x", "1",
    ];
    let mut c = Choices(0x9e37_79b9_7f4a_7c15);
    let (mut parsed, mut alone) = (0, 0);
    for text in &texts {
        parsed += usize::from(same_as_pest(text));
        alone += usize::from(read_alone(text));
        for _ in 0..6 {
            let mut t = text.clone();
            let at = c.next(t.len() + 1);
            let at = (0..=at).rev().find(|&i| t.is_char_boundary(i)).unwrap_or(0);
            match t[at..].chars().next() {
                Some(ch) if c.next(2) == 0 => t.replace_range(at..at + ch.len_utf8(), ""),
                _ => t.insert_str(at, c.pick(&tokens)),
            }
            same_as_pest(&t);
        }
    }
    assert!(alone > 0 && parsed > texts.len() / 2, "{alone}, {parsed}");
}
