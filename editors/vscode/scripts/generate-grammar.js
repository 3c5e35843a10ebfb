#!/usr/bin/env node
// Writes syntaxes/scn.tmLanguage.json: the grammar's structure is below, its word lists are read
// from the sources that define them, so the highlighting cannot drift from the language:
//   - property keywords, directive words and `rgb`'s spellings from grammar/scene.pest;
//   - built-in functions and constants from src/eval/builtins.rs and src/eval/random.rs, the
//     animation names from src/scene/animation.rs;
//   - the standard library's names from src/eval/stdlib/*.scn.
// `node scripts/generate-grammar.js --check` writes nothing and fails if the committed file
// differs from what it would write (test/tokenize.js runs it).
"use strict";

const fs = require("fs");
const path = require("path");

const here = __dirname;
const repo = path.resolve(here, "..", "..", "..");
const output = path.resolve(here, "..", "syntaxes", "scn.tmLanguage.json");

function fail(message) {
  throw new Error(`generate-grammar: ${message}`);
}

function read(rel) {
  return fs.readFileSync(path.join(repo, rel), "utf8");
}

/** The text of pest rule `name` (from `name = ...{` to its closing brace at depth 0). */
function pestRule(pest, name) {
  const start = pest.search(new RegExp(`^${name}\\s*=\\s*[_@$]?\\{`, "m"));
  if (start < 0) fail(`rule \`${name}\` not found in grammar/scene.pest`);
  let depth = 0;
  let inString = false;
  for (let i = pest.indexOf("{", start); i < pest.length; i++) {
    const c = pest[i];
    if (inString) {
      if (c === "\\") i++;
      else if (c === '"') inString = false;
    } else if (c === '"') inString = true;
    else if (c === "{") depth++;
    else if (c === "}" && --depth === 0) return pest.slice(pest.indexOf("{", start) + 1, i);
  }
  fail(`rule \`${name}\` is not closed`);
}

/** The tokens of a pest expression: string literals, character ranges, operators. */
function pestTokens(body) {
  const tokens = [];
  const re = /\s+|"((?:[^"\\]|\\.)*)"|'(.)'\s*\.\.\s*'(.)'|([()|~&!])|([A-Za-z_][A-Za-z0-9_]*)/gy;
  let m;
  while (re.lastIndex < body.length) {
    const at = re.lastIndex;
    if (!(m = re.exec(body))) fail(`cannot read \`${body.slice(at, at + 20)}\` in the grammar`);
    if (m[1] !== undefined) tokens.push({ lit: m[1] });
    else if (m[2] !== undefined) tokens.push({ range: [m[2], m[3]] });
    else if (m[4] !== undefined) tokens.push({ op: m[4] });
    else if (m[5] !== undefined) tokens.push({ rule: m[5] });
  }
  return tokens;
}

/**
 * The words a pest expression of literals matches: sequences (`~`) concatenate, choices (`|`)
 * unite, lookaheads (`&...`, `!...`) match no text. Any other rule name inside is an error, so a
 * new form in the grammar stops the generator instead of dropping words.
 */
function pestWords(body, allowedRules = []) {
  const tokens = pestTokens(body);
  let i = 0;
  function choice() {
    let words = sequence();
    while (tokens[i] && tokens[i].op === "|") {
      i++;
      words = words.concat(sequence());
    }
    return words;
  }
  function sequence() {
    let words = [""];
    for (;;) {
      const t = tokens[i];
      if (t && (t.op === "&" || t.op === "!")) {
        i++;
        primary(); // a lookahead: consumes no text
      } else {
        const part = primary();
        const joined = [];
        for (const a of words) for (const b of part) joined.push(a + b);
        words = joined;
      }
      if (tokens[i] && tokens[i].op === "~") i++;
      else return words;
    }
  }
  function primary() {
    const t = tokens[i++];
    if (!t) fail("unexpected end of a rule");
    if (t.lit !== undefined) return [JSON.parse(`"${t.lit}"`)];
    // A range of one character (`'#'..'#'`, which pest matches faster than "#") is that
    // character; any wider range stands for no fixed text (a lookahead's class).
    if (t.range) return t.range[0] === t.range[1] ? [t.range[0]] : [""];
    if (t.rule && allowedRules.includes(t.rule)) return [""];
    if (t.op === "(") {
      const words = choice();
      if (!tokens[i] || tokens[i].op !== ")") fail("unbalanced parentheses in a rule");
      i++;
      return words;
    }
    fail(`unexpected ${JSON.stringify(t)} in a rule of literals`);
  }
  const words = choice();
  if (i !== tokens.length) fail("trailing tokens in a rule of literals");
  return words;
}

/** The string literals of a Rust `const NAME: ... = [ ... ];` (first of each tuple if tuples). */
function rustConstStrings(rel, name) {
  const text = read(rel);
  const start = text.search(new RegExp(`const ${name}\\b`));
  if (start < 0) fail(`\`${name}\` not found in ${rel}`);
  const open = text.indexOf("= ", start);
  const end = text.indexOf("];", open);
  const body = text.slice(open, end);
  const tuples = [...body.matchAll(/\(\s*"([^"]+)"/g)].map((m) => m[1]);
  const words = tuples.length > 0 ? tuples : [...body.matchAll(/"([^"]+)"/g)].map((m) => m[1]);
  if (words.length === 0) fail(`no names in \`${name}\` (${rel})`);
  return words;
}

/** The names the standard file declares. */
function stdlibNames(rel) {
  const names = [...read(rel).matchAll(/^#declare\s+([A-Za-z_][A-Za-z0-9_]*)/gm)].map((m) => m[1]);
  if (names.length === 0) fail(`no declarations in ${rel}`);
  return names;
}

/** `\b(?:a|b|...)\b` of a word list, longest first (so that a prefix never shadows a word). */
// An expression between `open` and `close`. A `}` cannot stand inside parentheses or
// brackets (only inside a block of its own): one there ends them, so a parenthesis left open
// while typing does not run on.
function enclosed(what, open, close) {
  return {
    name: `meta.${what}.scn`,
    begin: open,
    end: `${close}|(?=\\})`,
    beginCaptures: { 0: { name: `punctuation.section.${what}.begin.scn` } },
    endCaptures: { 0: { name: `punctuation.section.${what}.end.scn` } },
    patterns: [{ include: "#expression" }],
  };
}

function wordsPattern(words, { after = "", before = "" } = {}) {
  const sorted = [...new Set(words)].sort((a, b) => b.length - a.length || (a < b ? -1 : 1));
  return `${before}\\b(?:${sorted.join("|")})\\b${after}`;
}

function lists() {
  const pest = read("grammar/scene.pest");
  const keywords = pestWords(pestRule(pest, "kw_word"));
  const directives = pestWords(pestRule(pest, "dword"), ["ident_char"]).map((w) => {
    if (!w.startsWith("#")) fail(`directive word without #: ${w}`);
    return w.slice(1);
  });
  const rgb = pestWords(pestRule(pest, "rgb"), ["ident_char"]);
  const functions = [
    ...rustConstStrings("src/eval/builtins.rs", "FUNCTIONS"),
    ...rustConstStrings("src/eval/random.rs", "RANDOM_FUNCTIONS"),
  ];
  const constants = rustConstStrings("src/eval/builtins.rs", "CONSTANTS");
  const animation = rustConstStrings("src/scene/animation.rs", "ANIMATION_NAMES");
  const colours = stdlibNames("src/eval/stdlib/colors.scn");
  const materials = stdlibNames("src/eval/stdlib/materials.scn");
  return { keywords, directives, rgb, functions, constants, animation, colours, materials };
}

const IDENT = "[A-Za-z_][A-Za-z0-9_]*";

function grammar(l) {
  // Words of a directive, in the order the grammar's `dword` gives (longest first there).
  const control = ["if", "ifdef", "ifndef", "elif", "else", "end", "while", "for", "switch",
    "case", "range", "break"];
  const unknownDirective = l.directives.filter((d) => !control.includes(d) &&
    !["declare", "local", "macro", "undef", "include", "debug", "warning", "error"].includes(d));
  if (unknownDirective.length > 0) {
    fail(`directive(s) ${unknownDirective.join(", ")} have no highlighting rule: add them`);
  }
  for (const c of control) {
    if (!l.directives.includes(c)) fail(`#${c} is no longer a directive of the grammar`);
  }
  // Top-level alternatives: a look-behind takes them of different lengths, not a group.
  const notOperand = [...l.keywords, ...l.rgb, "color", "colour"].map((w) => `\\b${w}`).join("|");
  const item = [
    { include: "#comments" },
    { include: "#directives" },
    { include: "#strings" },
    { include: "#vector" },
    { include: "#block" },
    { include: "#parens" },
    { include: "#array" },
    { include: "#numbers" },
    { include: "#words" },
    { include: "#operators" },
    { include: "#punctuation" },
    { include: "#invalid" },
    // Among items, a `)` or `]` closes nothing (they end parentheses and brackets).
    { match: "[)\\]]", name: "invalid.illegal.stray-bracket.scn" },
  ];
  return {
    $schema: "https://raw.githubusercontent.com/martinring/tmlanguage/master/tmlanguage.json",
    name: "sppm-lang scene",
    scopeName: "source.scn",
    fileTypes: ["scn"],
    comment:
      "Generated by editors/vscode/scripts/generate-grammar.js from grammar/scene.pest and the " +
      "evaluator's name lists: edit the script, not this file.",
    // At the top level a `}` closes nothing: the parser stops there.
    patterns: [{ include: "#items" }, { match: "\\}", name: "invalid.illegal.stray-bracket.scn" }],
    repository: {
      // A file and the inside of `{ ... }`: items, where `<` always opens a vector.
      items: { patterns: item },
      // Inside `( ... )` and `[ ... ]`: an expression, where `<` after an operand compares.
      expression: { patterns: [...item.slice(0, 3), { include: "#comparison" }, ...item.slice(3)] },
      comments: {
        patterns: [
          {
            name: "comment.line.double-slash.scn",
            match: "(//).*$",
            captures: { 1: { name: "punctuation.definition.comment.scn" } },
          },
          { include: "#block-comment" },
        ],
      },
      // Block comments nest, as the parser reads them.
      "block-comment": {
        name: "comment.block.scn",
        begin: "/\\*",
        end: "\\*/",
        beginCaptures: { 0: { name: "punctuation.definition.comment.begin.scn" } },
        endCaptures: { 0: { name: "punctuation.definition.comment.end.scn" } },
        patterns: [{ include: "#block-comment" }],
      },
      strings: {
        name: "string.quoted.double.scn",
        begin: '"',
        beginCaptures: { 0: { name: "punctuation.definition.string.begin.scn" } },
        // A string ends at its quote; a line break inside one (not escaped) is an error.
        end: '(")|(\\n)',
        endCaptures: {
          1: { name: "punctuation.definition.string.end.scn" },
          2: { name: "invalid.illegal.unclosed-string.scn" },
        },
        patterns: [
          { name: "constant.character.escape.scn", match: '\\\\["\\\\nt]' },
          // The parser accepts a backslash before a line break (the string goes on).
          { name: "constant.character.escape.scn", match: "\\\\\\n" },
          { name: "invalid.illegal.escape.scn", match: "\\\\." },
        ],
      },
      directives: {
        patterns: [
          {
            match: `((#)(?:declare|local))\\b(?:\\s+(${IDENT}))?`,
            captures: {
              1: { name: "keyword.other.directive.declare.scn" },
              2: { name: "punctuation.definition.directive.scn" },
              3: { name: "variable.other.declaration.scn" },
            },
          },
          {
            match: `((#)(?:macro))\\b(?:\\s+(${IDENT}))?`,
            captures: {
              1: { name: "keyword.other.directive.macro.scn" },
              2: { name: "punctuation.definition.directive.scn" },
              3: { name: "entity.name.function.macro.scn" },
            },
          },
          {
            match: `((#)(?:undef))\\b(?:\\s+(${IDENT}))?`,
            captures: {
              1: { name: "keyword.other.directive.undef.scn" },
              2: { name: "punctuation.definition.directive.scn" },
              3: { name: "variable.other.scn" },
            },
          },
          {
            match: "(#)include\\b",
            name: "keyword.control.import.scn",
            captures: { 1: { name: "punctuation.definition.directive.scn" } },
          },
          {
            match: `(#)(?:${control.join("|")})\\b`,
            name: "keyword.control.directive.scn",
            captures: { 1: { name: "punctuation.definition.directive.scn" } },
          },
          {
            match: "(#)(?:debug|warning|error)\\b",
            name: "keyword.other.directive.message.scn",
            captures: { 1: { name: "punctuation.definition.directive.scn" } },
          },
          // Any other `#word` is not a directive: the parser stops there.
          { match: "#[A-Za-z0-9_]*", name: "invalid.illegal.directive.scn" },
        ],
      },
      // `<` opens a vector when its `>` follows on the line before any `<`, brace, `;` or `#`.
      vector: {
        name: "meta.vector.scn",
        begin: "<(?!=)(?=[^<>{};#]*>)",
        end: ">",
        beginCaptures: { 0: { name: "punctuation.definition.vector.begin.scn" } },
        endCaptures: { 0: { name: "punctuation.definition.vector.end.scn" } },
        // Inside, only arithmetic applies (the parser's `vexpr`): `>` always closes.
        patterns: [
          { include: "#comments" },
          { include: "#strings" },
          { include: "#vector" },
          { include: "#block" },
          { include: "#parens" },
          { include: "#array" },
          { include: "#numbers" },
          { include: "#words" },
          { match: "[-+*/]", name: "keyword.operator.arithmetic.scn" },
          { include: "#punctuation" },
          { include: "#invalid" },
        ],
      },
      block: {
        name: "meta.block.scn",
        begin: "\\{",
        end: "\\}",
        beginCaptures: { 0: { name: "punctuation.section.block.begin.scn" } },
        endCaptures: { 0: { name: "punctuation.section.block.end.scn" } },
        // At the top level a `}` closes nothing: the parser stops there.
    patterns: [{ include: "#items" }, { match: "\\}", name: "invalid.illegal.stray-bracket.scn" }],
      },
      parens: enclosed("parens", "\\(", "\\)"),
      array: enclosed("brackets", "\\[", "\\]"),
      numbers: {
        name: "constant.numeric.scn",
        match: "(?<![A-Za-z0-9_.])(?:[0-9]+(?:\\.[0-9]*)?|\\.[0-9]+)(?:[eE][+-]?[0-9]+)?",
      },
      words: {
        patterns: [
          // After `.`: a field (`v.x`, `c.red`), whatever the word.
          { match: `(?<=\\.)${IDENT}`, name: "variable.other.member.scn" },
          { match: wordsPattern(l.keywords), name: "keyword.other.property.scn" },
          { match: wordsPattern(l.rgb), name: "storage.type.colour.scn" },
          { match: "\\b(?:true|false)\\b", name: "constant.language.boolean.scn" },
          { match: "\\bfunction\\b(?=\\s*[({])", name: "storage.type.function.scn" },
          { match: wordsPattern(l.functions, { after: "(?=\\s*\\()" }), name: "support.function.builtin.scn" },
          { match: wordsPattern([...l.constants, ...l.animation]), name: "support.constant.builtin.scn" },
          { match: wordsPattern(l.colours), name: "support.constant.colour.scn" },
          { match: wordsPattern(l.materials), name: "support.constant.material.scn" },
          // `name {` opens a block (an object, a material, ...); `name(` calls a macro.
          { match: `${IDENT}(?=\\s*\\{)`, name: "entity.name.type.block.scn" },
          { match: `${IDENT}(?=\\s*\\()`, name: "entity.name.function.call.scn" },
          { match: IDENT, name: "variable.other.scn" },
        ],
      },
      // Only in an expression (parentheses, brackets): `<`, `>` right after an operand, which
      // a keyword is not (`[0.5 rgb <1, 0, 0>]`, `[0 color Red]` in a colour map).
      comparison: {
        match: `(?<=[A-Za-z0-9_)\\]])(?<!${notOperand})\\s*(<=?|>=?)`,
        captures: { 1: { name: "keyword.operator.comparison.scn" } },
      },
      operators: {
        patterns: [
          { match: "==|!=|<=|>=|<|>", name: "keyword.operator.comparison.scn" },
          { match: "&&|\\|\\||&|\\||!", name: "keyword.operator.logical.scn" },
          { match: "[-+*/]", name: "keyword.operator.arithmetic.scn" },
          { match: "=", name: "keyword.operator.assignment.scn" },
          { match: "[?:]", name: "keyword.operator.ternary.scn" },
        ],
      },
      punctuation: {
        patterns: [
          { match: ",", name: "punctuation.separator.comma.scn" },
          { match: ";", name: "punctuation.terminator.scn" },
          { match: "\\.", name: "punctuation.accessor.scn" },
        ],
      },
      // Characters the language has no use for outside strings and comments (a byte order mark
      // may open the file).
      invalid: {
        match: "[@$%^~`'\\\\]|[^\\x{00}-\\x{7F}\\x{FEFF}]",
        name: "invalid.illegal.character.scn",
      },
    },
  };
}

function generate() {
  return `${JSON.stringify(grammar(lists()), null, 2)}\n`;
}

module.exports = { generate, lists, output };

if (require.main === module) {
  const text = generate();
  if (process.argv.includes("--check")) {
    const committed = fs.existsSync(output) ? fs.readFileSync(output, "utf8") : "";
    if (committed !== text) {
      console.error(
        "syntaxes/scn.tmLanguage.json is not what scripts/generate-grammar.js writes from the " +
          "current sources: run `npm run generate` in editors/vscode",
      );
      process.exit(1);
    }
    console.log("syntaxes/scn.tmLanguage.json is up to date");
  } else {
    fs.writeFileSync(output, text);
    const l = lists();
    console.log(
      `wrote ${path.relative(process.cwd(), output)}: ${l.keywords.length} keywords, ` +
        `${l.directives.length} directives, ${l.functions.length} functions, ` +
        `${l.colours.length + l.materials.length} standard names`,
    );
  }
}
