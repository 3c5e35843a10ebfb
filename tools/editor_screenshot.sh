#!/usr/bin/env bash
# Takes docs/gallery/editor.png, the README's picture of editor support: Neovim's built-in
# language client talking to `sppm-lang lsp`, in an xterm on a virtual screen (Xvfb), editing a
# small scene with a misspelt property. The script waits for the server's diagnostic, opens the
# completion list inside a block (omni completion, `<C-x><C-o>`, served by the server), and
# captures the screen with ImageMagick.
#
#   tools/editor_screenshot.sh [OUT.png]       (default docs/gallery/editor.png)
#
# Needs: neovim 0.7 or later, xvfb, xterm, imagemagick, x11-utils and fonts-dejavu-core
# (`apt-get install neovim xvfb xterm imagemagick x11-utils fonts-dejavu-core`), and a built
# sppm-lang: $SPPM_LANG, else $CARGO_TARGET_DIR/debug/sppm-lang, else target/debug/sppm-lang.
# Neovim has no TextMate grammars: the colours are Vim's POV-Ray syntax file, close enough for
# a picture (VS Code uses editors/vscode/syntaxes/scn.tmLanguage.json).
set -euo pipefail
cd "$(dirname "$0")/.."

out=${1:-docs/gallery/editor.png}
bin=${SPPM_LANG:-${CARGO_TARGET_DIR:-target}/debug/sppm-lang}
bin=$(realpath "$bin")
for tool in nvim Xvfb xterm import convert xwininfo; do
  command -v "$tool" >/dev/null || { echo "error: $tool is not installed" >&2; exit 1; }
done
[ -x "$bin" ] || { echo "error: no sppm-lang at $bin (build it, or set SPPM_LANG)" >&2; exit 1; }

work=$(mktemp -d)
pids=()
cleanup() {
  # The terminal before the X server it draws on.
  for ((i = ${#pids[@]} - 1; i >= 0; i--)); do
    kill "${pids[$i]}" 2>/dev/null || true
    wait "${pids[$i]}" 2>/dev/null || true
  done
  rm -rf "$work"
}
trap cleanup EXIT

# The scene being edited: `difuse` is the mistake; line 9 is where the completion opens.
cat >"$work/scene.scn" <<'EOF'
// A red ball on a floor, half edited: one word is misspelt.
#include "std/colors.scn"
camera { location <0, 1.5, -5> look_at <0, 1, 0> }
light { <2, 6, -4> intensity 60 }
plane { y, 0 material { diffuse White } }
sphere {
  <0, 1, 0>, 1
  material { difuse Red }
  
}
EOF

# Neovim's setup: the server as docs/editors.md configures it (0.7 has no vim.lsp.start, so
# start_client + buf_attach_client), then the steps on a timer: wait for the diagnostic, open
# the completion list, and say "ready" once it shows (or "failed: why" after 60 s).
cat >"$work/init.lua" <<'EOF'
local dir = os.getenv("SHOT_DIR")
vim.o.termguicolors = true
vim.o.background = "dark"
vim.o.number = true
vim.o.signcolumn = "yes"
vim.o.laststatus = 2
vim.o.completeopt = "menuone,noinsert"
vim.o.pumheight = 8
vim.o.swapfile = false
vim.cmd("syntax on")
vim.cmd("highlight Normal guibg=#1e1e1e guifg=#d4d4d4")
vim.cmd("highlight LineNr guifg=#858585")
vim.cmd("highlight EndOfBuffer guifg=#1e1e1e")
vim.cmd("highlight SignColumn guibg=#1e1e1e")
vim.cmd("highlight Pmenu guibg=#252526 guifg=#d4d4d4")
vim.cmd("highlight PmenuSel guibg=#04395e guifg=#ffffff")
vim.cmd("highlight PmenuSbar guibg=#333333")
vim.cmd("highlight PmenuThumb guibg=#6e6e6e")
vim.cmd("highlight DiagnosticError guifg=#f14c4c")
vim.cmd("highlight DiagnosticVirtualTextError guifg=#f14c4c guibg=#3a1d1d")
vim.cmd("highlight DiagnosticUnderlineError gui=undercurl guisp=#f14c4c")
vim.cmd("highlight StatusLine guibg=#007acc guifg=#ffffff gui=NONE")

vim.api.nvim_create_autocmd({ "BufRead", "BufNewFile" }, {
  pattern = "*.scn",
  callback = function() vim.bo.filetype = "scn" end,
})
local client_id
vim.api.nvim_create_autocmd("FileType", {
  pattern = "scn",
  callback = function(args)
    vim.bo[args.buf].syntax = "pov"
    client_id = client_id or vim.lsp.start_client({
      name = "sppm-lang",
      cmd = { os.getenv("SPPM_LANG"), "lsp" },
      root_dir = dir,
    })
    vim.lsp.buf_attach_client(args.buf, client_id)
    vim.bo[args.buf].omnifunc = "v:lua.vim.lsp.omnifunc"
  end,
})

local function say(text)
  local f = io.open(dir .. "/status", "w")
  f:write(text)
  f:close()
end
local started = vim.loop.now()
local step = "diagnostic"
local timer = vim.loop.new_timer()
timer:start(300, 200, vim.schedule_wrap(function()
  if vim.loop.now() - started > 60000 then
    timer:stop()
    local clients = #vim.lsp.get_active_clients()
    say(("failed: no %s after 60 s (%d language client(s) running)"):format(step, clients))
  elseif step == "diagnostic" and #vim.diagnostic.get(0) > 0 then
    step = "completion list"
    vim.api.nvim_win_set_cursor(0, { 9, 0 })
    local keys = vim.api.nvim_replace_termcodes("A<C-x><C-o>", true, false, true)
    vim.api.nvim_feedkeys(keys, "n", false)
  elseif step == "completion list" and vim.fn.pumvisible() == 1 then
    step = "done"
    -- Let the screen settle before the capture.
    vim.defer_fn(function() timer:stop() say("ready") end, 700)
  end
end))
EOF

# A free display number.
display=90
while [ -e "/tmp/.X11-unix/X$display" ] || [ -e "/tmp/.X$display-lock" ]; do display=$((display + 1)); done
Xvfb ":$display" -screen 0 1800x900x24 -nolisten tcp >"$work/xvfb.log" 2>&1 &
pids+=($!)
export DISPLAY=":$display"
for _ in $(seq 50); do xwininfo -root >/dev/null 2>&1 && break; sleep 0.1; done

(cd "$work" && SHOT_DIR="$work" SPPM_LANG="$bin" exec xterm -geometry 132x20+0+0 \
  -fa 'DejaVu Sans Mono' -fs 14 -bg '#1e1e1e' -fg '#d4d4d4' -b 8 -bw 0 \
  -xrm 'XTerm*termName: xterm-256color' -e nvim -u init.lua scene.scn) &
pids+=($!)

for _ in $(seq 700); do
  [ -s "$work/status" ] && break
  sleep 0.1
done
status=$(cat "$work/status" 2>/dev/null || echo "failed: neovim never reported")
if [ "$status" != ready ]; then
  echo "error: $status" >&2
  exit 1
fi

# The xterm's size on the screen (it sits at the top left, without a window manager's frame).
geometry=$(xwininfo -root -tree | awk '/xterm|XTerm|nvim/ && /\+0\+0/ { print $(NF-1); exit }')
geometry=${geometry%%+*}
import -window root "$work/screen.png"
mkdir -p "$(dirname "$out")"
convert "$work/screen.png" -crop "${geometry}+0+0" +repage -strip "$out"
echo "wrote $out ($geometry)"
