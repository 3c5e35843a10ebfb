#!/usr/bin/env bash
# Renders the per-material pictures of docs/language.md ("Materials") into
# docs/gallery/materials/: one sphere of each kind over a checker floor, under a gradient
# backdrop and an area light. Usage: tools/material_pictures.sh [path to sppm-lang]
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${1:-target/debug/sppm-lang}"
out=docs/gallery/materials
mkdir -p "$out"
declare -A kinds=(
  [diffuse]='diffuse rgb <0.8, 0.35, 0.2>'
  [mirror]='mirror'
  [glass]='glass ior 1.5'
  [frosted]='glass ior 1.5 roughness 0.3'
  [thin]='glass thin tint rgb <0.85, 0.95, 0.9>'
  [glossy]='glossy rgb <0.2, 0.35, 0.8> roughness 0.25'
  [conductor]='conductor "Au" roughness 0.2'
  [coated]='coated rgb <0.7, 0.15, 0.1> roughness 0.1'
  [blend]='blend material { diffuse rgb <0.8, 0.6, 0.4> }, material { mirror } weight 0.3'
  [bumps]='coated rgb <0.6, 0.05, 0.04> roughness 0.1 normal { wrinkles 0.5 scale 0.25 }'
)
scene=$(mktemp --suffix=.scn)
trap 'rm -f "$scene"' EXIT
for k in "${!kinds[@]}"; do
  cat > "$scene" <<SCN
settings { resolution <128, 96>  iterations 40  photons 100000  seed 3 }
camera { location <0, 1.3, -3.2> look_at <0, 0.6, 0> fov 38 }
background texture { gradient y color_map { [0 rgb <0.9, 0.9, 0.85>] [1 rgb <0.25, 0.4, 0.8>] } }
area_light { quad { <-0.6, 3, -1.2>, <1.2, 0, 0>, <0, 0, 1.2> } radiance rgb 9 }
plane { <0, 1, 0>, 0 material { diffuse texture { checker rgb 0.75, rgb 0.15 scale 0.5 } } }
sphere { <0, 0.7, 0>, 0.7 material { ${kinds[$k]} } }
SCN
  "$bin" render "$scene" -o "$out/$k.png"
done
