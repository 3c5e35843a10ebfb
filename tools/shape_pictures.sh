#!/usr/bin/env bash
# Renders the per-shape pictures of docs/language.md into docs/gallery/shapes/: each shape of
# POV-Ray's family on its own over a checker floor, under a gradient backdrop and an area
# light. Usage: tools/shape_pictures.sh [path to sppm-lang]
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${1:-target/debug/sppm-lang}"
out=docs/gallery/shapes
mkdir -p "$out"
declare -A shapes=(
  [prism]='prism { bezier_spline 0, 0.5, 8,
      <-0.6, 0>, <-0.6, 0.8>, <0.6, 0.8>, <0.6, 0>, <0.6, 0>, <0.6, -0.8>, <-0.6, -0.8>, <-0.6, 0>
      rotate <0, 30, 0> translate <0, 0.05, 0> material { glass ior 1.5 } }'
  [superellipsoid]='superellipsoid { <0.3, 0.6> scale 0.6 rotate <0, 30, 0> translate <0, 0.65, 0>
      material { conductor "Cu" roughness 0.15 } }'
  [sphere_sweep]='sphere_sweep { linear_spline 4, <-0.8, 0.15, 0>, 0.12, <-0.3, 0.9, 0.2>, 0.2,
      <0.3, 0.5, -0.1>, 0.1, <0.8, 1.1, 0>, 0.15 material { coated rgb <0.7, 0.1, 0.1> roughness 0.1 } }'
  [sphere_sweep_b_spline]='sphere_sweep { b_spline 7, <-1.1, 0.2, 0>, 0.05, <-0.7, 1.0, 0.1>, 0.18,
      <-0.2, 0.15, -0.2>, 0.12, <0.2, 1.0, 0.2>, 0.2, <0.6, 0.2, 0>, 0.1, <1.0, 0.9, -0.1>, 0.12,
      <1.2, 0.4, 0>, 0 material { conductor "Au" roughness 0.1 } }'
  [blob]='blob { threshold 0.6
      sphere { <-0.3, 0, 0>, 0.7, strength 1 } sphere { <0.3, 0.05, 0>, 0.65, strength 1 }
      sphere { <0, 0.4, 0.05>, 0.6, strength 1 } sphere { <0, 0.1, -0.35>, 0.4, strength -1 }
      translate <0, 0.45, 0> material { conductor "Ag" roughness 0.1 } }'
  [isosurface]='isosurface {
      function { sqrt(x * x + y * y + z * z) - 0.5 + 0.04 * sin(14 * x) * sin(14 * y) * sin(14 * z) }
      contained_by { box { <-0.6, -0.6, -0.6>, <0.6, 0.6, 0.6> } }
      translate <0, 0.6, 0> material { glass ior 1.5 } }'
  [height_field]='height_field { function 101, 101 { 0.5 + 0.3 * sin(9 * x) * cos(7 * y) }
      smooth water_level 0.1 translate <-0.5, 0, -0.5> scale <1.8, 0.6, 1.8>
      material { diffuse rgb <0.45, 0.52, 0.32> } }'
  [text]='text { ttf "DejaVuSans.ttf" "Text" 0.2, 0 scale 0.8 rotate <0, 180, 0> translate <1.2, 0.05, 0>
      material { conductor "Au" roughness 0.05 } }'
)
scene=$(mktemp --suffix=.scn)
trap 'rm -f "$scene"' EXIT
for k in "${!shapes[@]}"; do
  cat > "$scene" <<SCN
settings { resolution <128, 96>  iterations 40  photons 100000  seed 3 }
camera { location <0, 1.5, -3.2> look_at <0, 0.5, 0> fov 38 }
background texture { gradient y color_map { [0 rgb <0.9, 0.9, 0.85>] [1 rgb <0.25, 0.4, 0.8>] } }
area_light { quad { <-0.6, 3, -1.2>, <1.2, 0, 0>, <0, 0, 1.2> } radiance rgb 9 }
plane { <0, 1, 0>, 0 material { diffuse texture { checker rgb 0.75, rgb 0.15 scale 0.5 } } }
${shapes[$k]}
SCN
  "$bin" render "$scene" -o "$out/$k.png"
done
