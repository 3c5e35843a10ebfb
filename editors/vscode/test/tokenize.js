#!/usr/bin/env node
// The TextMate grammar against the repository's scenes, tokenized as VS Code does (the npm
// packages vscode-textmate and vscode-oniguruma, the editor's own engine):
//
// 1. syntaxes/scn.tmLanguage.json is what scripts/generate-grammar.js makes from the sources
//    (keywords from grammar/scene.pest, names from the evaluator), so it cannot drift;
// 2. every examples/**/*.scn, tests/good/**/*.scn and tests/bad/**/*.scn is tokenized. A file
//    the parser accepts must end with the grammar back at the top level (no string, comment,
//    block, parenthesis or vector left open) and have no token scoped `invalid`. A file the
//    parser rejects may have either (an unclosed comment does colour the rest of the file):
//    the parser's verdict per file comes from `--verdicts FILE` (a JSON list of the files it
//    rejects, relative to the repository; the Rust test tests/cli/editor_grammar.rs writes it
//    with sppm_lang::syntax::parse). Without it, examples/ and tests/good/ are taken as accepted
//    and tests/bad/ is only counted;
// 3. a few snippets get the scopes they should (a keyword, a directive, a comment, ...).
//
// Exit status 0 when all hold; the failures are listed otherwise.
"use strict";

const fs = require("fs");
const path = require("path");
const vsctm = require("vscode-textmate");
const oniguruma = require("vscode-oniguruma");
const { generate, output: grammarPath } = require("../scripts/generate-grammar.js");

const repo = path.resolve(__dirname, "..", "..", "..");
const failures = [];

function fail(message) {
  failures.push(message);
}

async function loadGrammar() {
  const wasm = fs.readFileSync(require.resolve("vscode-oniguruma/release/onig.wasm"));
  await oniguruma.loadWASM(wasm.buffer.slice(wasm.byteOffset, wasm.byteOffset + wasm.length));
  const registry = new vsctm.Registry({
    onigLib: Promise.resolve({
      createOnigScanner: (patterns) => new oniguruma.OnigScanner(patterns),
      createOnigString: (s) => new oniguruma.OnigString(s),
    }),
    loadGrammar: async (scopeName) =>
      scopeName === "source.scn"
        ? vsctm.parseRawGrammar(fs.readFileSync(grammarPath, "utf8"), grammarPath)
        : null,
  });
  return registry.loadGrammar("source.scn");
}

/** Tokens of `text` as `{ line, text, scopes }`, and the rule stack at the end. */
function tokenize(grammar, text) {
  // The editor drops a byte order mark and splits lines at \r\n, \r and \n.
  const lines = text.replace(/^\uFEFF/, "").split(/\r\n|\r|\n/);
  let stack = vsctm.INITIAL;
  const tokens = [];
  lines.forEach((line, n) => {
    const r = grammar.tokenizeLine(line, stack);
    for (const t of r.tokens) {
      tokens.push({
        line: n + 1,
        column: t.startIndex + 1,
        text: line.slice(t.startIndex, t.endIndex),
        scopes: t.scopes,
      });
    }
    stack = r.ruleStack;
  });
  return { tokens, stack };
}

/** The scopes still open at the end, innermost last (empty at the top level). */
function openScopes(stack) {
  const open = [];
  for (let s = stack; s && s.depth > 1; s = s.parent) {
    open.unshift(s.contentNameScopesList?.scopeName ?? s.nameScopesList?.scopeName ?? "?");
  }
  return open;
}

function scnFiles(dir) {
  const out = [];
  const walk = (d) => {
    for (const e of fs.readdirSync(d, { withFileTypes: true })) {
      const p = path.join(d, e.name);
      if (e.isDirectory()) walk(p);
      else if (e.isFile() && e.name.endsWith(".scn")) out.push(p);
    }
  };
  walk(path.join(repo, dir));
  return out.sort();
}

function checkGenerated() {
  if (fs.readFileSync(grammarPath, "utf8") !== generate()) {
    fail(
      "syntaxes/scn.tmLanguage.json differs from what scripts/generate-grammar.js makes from the " +
        "current grammar and name lists: run `npm run generate` in editors/vscode",
    );
  }
}

function checkFiles(grammar, rejected) {
  const counts = { files: 0, accepted: 0, rejected: 0, unjudged: 0, tokens: 0 };
  const rejectedWith = { open: [], invalid: [] };
  for (const dir of ["examples", "tests/good", "tests/bad"]) {
    for (const file of scnFiles(dir)) {
      const rel = path.relative(repo, file).split(path.sep).join("/");
      const { tokens, stack } = tokenize(grammar, fs.readFileSync(file, "utf8"));
      counts.files++;
      counts.tokens += tokens.length;
      const open = openScopes(stack);
      const invalid = tokens.filter((t) => t.scopes.some((s) => s.startsWith("invalid")));
      const verdict = rejected ? !rejected.has(rel) : !rel.startsWith("tests/bad/");
      if (rejected && rejected.has(rel)) {
        counts.rejected++;
        if (open.length > 0) rejectedWith.open.push(`${rel} (${open.join(" > ")})`);
        if (invalid.length > 0) rejectedWith.invalid.push(rel);
      } else if (!rejected && rel.startsWith("tests/bad/")) {
        counts.unjudged++;
      } else if (verdict) {
        counts.accepted++;
        if (open.length > 0) {
          fail(`${rel}: the parser accepts it, but it ends inside ${open.join(" > ")}`);
        }
        for (const t of invalid.slice(0, 3)) {
          fail(`${rel}:${t.line}:${t.column}: \`${t.text}\` is scoped ${t.scopes.at(-1)}, but the parser accepts the file`);
        }
      }
    }
  }
  if (rejected) {
    for (const rel of rejected) {
      if (!fs.existsSync(path.join(repo, rel))) fail(`--verdicts names ${rel}, which does not exist`);
    }
  }
  return { counts, rejectedWith };
}

/** Snippets and the scope each marked piece must have (the innermost scope starts with it). */
const SNIPPETS = [
  ["sphere { <0, 1, 0>, 1.5 }", { sphere: "entity.name.type.block", "<": "punctuation.definition.vector.begin", "1.5": "constant.numeric", ">": "punctuation.definition.vector.end" }],
  ["object { Ball translate <1, 0, 0> }", { translate: "keyword.other.property", Ball: "variable.other" }],
  ["#declare Size = 2e-3;", { "#declare": "keyword.other.directive.declare", Size: "variable.other.declaration", "2e-3": "constant.numeric" }],
  ["#macro Ball(P) sphere { P, 1 } #end", { "#macro": "keyword.other.directive.macro", Ball: "entity.name.function.macro", "#end": "keyword.control.directive" }],
  ["#if (N < 2 & M > 1) #end", { "<": "keyword.operator.comparison", ">": "keyword.operator.comparison" }],
  ["color_map { [0.5 rgb <1, 0, 0>] }", { "<": "punctuation.definition.vector.begin", ">": "punctuation.definition.vector.end" }],
  ['#include "std/colors.scn"', { "#include": "keyword.control.import", '"std/colors.scn"': "string.quoted.double" }],
  ['#debug "a\\"b\\n"', { '\\"': "constant.character.escape", "\\n": "constant.character.escape" }],
  ['image "C:\\wood.png"', { "\\w": "invalid.illegal.escape", image: "keyword.other.property" }],
  ["light { <0, 5, 0> intensity 10 } // the key light", { "// the key light": "comment.line.double-slash", intensity: "keyword.other.property" }],
  ["/* a /* nested */ still */ plane", { still: "comment.block", plane: "variable.other" }],
  ["material { diffuse rgb <0.8, 0.1, 0.1> }", { rgb: "storage.type.colour", diffuse: "keyword.other.property" }],
  ["pigment { Red } material { Glass }", { Red: "support.constant.colour", Glass: "support.constant.material" }],
  ["#declare A = sqrt(2) * pi + clock;", { sqrt: "support.function.builtin", pi: "support.constant.builtin", clock: "support.constant.builtin" }],
  ["spline { degree 1 <0, 0> }", { degree: "keyword.other.property", "<": "punctuation.definition.vector.begin" }],
  ["#delcare X = 1", { "#delcare": "invalid.illegal.directive" }],
  ["sphere { <0, 0, 0>, 1 ) }", { ")": "invalid.illegal.stray-bracket", "}": "punctuation.section.block.end" }],
  ["} sphere", { "}": "invalid.illegal.stray-bracket" }],
  ["image “tiles.png”", { "“": "invalid.illegal.character" }],
  ["#declare F = function(a) { a * 2 };", { function: "storage.type.function" }],
  ["#declare On = true;", { true: "constant.language.boolean" }],
];

function checkSnippets(grammar) {
  let assertions = 0;
  for (const [text, expected] of SNIPPETS) {
    const { tokens, stack } = tokenize(grammar, text);
    if (openScopes(stack).length > 0) fail(`snippet \`${text}\` ends inside ${openScopes(stack).join(" > ")}`);
    for (const [piece, scope] of Object.entries(expected)) {
      assertions++;
      // The tokens covering the first occurrence of `piece`, all of which must have the scope.
      const at = text.indexOf(piece);
      const covering = tokens.filter((t) => t.column - 1 < at + piece.length && t.column - 1 + t.text.length > at);
      const ok = covering.length > 0 && covering.every((t) => t.scopes.some((s) => s.startsWith(scope)));
      if (!ok) {
        const got = covering.map((t) => `\`${t.text}\`: ${t.scopes.slice(1).join(" ")}`).join("; ");
        fail(`snippet \`${text}\`: \`${piece}\` should be ${scope}, is ${got || "no token"}`);
      }
    }
  }
  // Across lines: a string left open ends at its line; a block comment goes on.
  const open = tokenize(grammar, '#debug "half\nsphere');
  const sphere = open.tokens.find((t) => t.text === "sphere");
  assertions++;
  if (!sphere || sphere.scopes.some((s) => s.startsWith("string"))) fail("a string left open at a line break must end there");
  const comment = tokenize(grammar, "/* begins\nsphere { }\n");
  assertions++;
  if (openScopes(comment.stack).join() !== "comment.block.scn") fail("an unclosed block comment must run to the end of the file");
  return assertions;
}

function argument(name) {
  const i = process.argv.indexOf(name);
  return i > 0 ? process.argv[i + 1] : undefined;
}

async function main() {
  const verdicts = argument("--verdicts");
  const rejected = verdicts ? new Set(JSON.parse(fs.readFileSync(verdicts, "utf8"))) : undefined;
  checkGenerated();
  const grammar = await loadGrammar();
  const { counts, rejectedWith } = checkFiles(grammar, rejected);
  const assertions = checkSnippets(grammar);
  console.log(
    `tokenized ${counts.files} files (${counts.tokens} tokens): ${counts.accepted} the parser ` +
      `accepts, ${counts.rejected} it rejects${rejected ? "" : ` (no --verdicts: ${counts.unjudged} in tests/bad not judged)`}`,
  );
  if (rejected) {
    console.log(`rejected files ending inside a region: ${rejectedWith.open.length}${rejectedWith.open.length ? ` (${rejectedWith.open.join(", ")})` : ""}`);
    console.log(`rejected files with an invalid token: ${rejectedWith.invalid.length}`);
  }
  console.log(`${assertions} scope assertions on ${SNIPPETS.length + 2} snippets`);
  if (failures.length > 0) {
    for (const f of failures) console.error(`FAIL ${f}`);
    console.error(`${failures.length} failure(s)`);
    process.exit(1);
  }
  console.log("grammar: all checks passed");
}

main().catch((err) => {
  console.error(err);
  process.exit(1);
});
