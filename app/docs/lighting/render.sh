#!/usr/bin/env bash
# Renders the images app/docs/lighting/README.md shows (README shows one, under "Default lighting"): the bundled material spheres
# (a model without light sources) as the old default lit them, by a uniform environment of
# radiance 1, and as the default rule lights them now, by the studio; and the studio turned
# half way round. PNG, automatic exposure, 512 x 256, 256 samples per pixel of the path tracer.
# Usage (about 2 minutes on 2 cores): bash app/docs/lighting/render.sh [AlphaBlendModeTest.gltf]
set -euo pipefail
cd "$(dirname "$0")/../../.."
cargo build --release -q
bin=target/release/caustica
out=app/docs/lighting
common=(--width 512 --height 256 --spp 256 --seed 1)
"$bin" render assets/material-spheres.gltf -o "$out/spheres-uniform.png" "${common[@]}" --environment uniform
"$bin" render assets/material-spheres.gltf -o "$out/spheres-studio.png" "${common[@]}"
"$bin" render assets/material-spheres.gltf -o "$out/spheres-studio-turned.png" "${common[@]}" \
  --environment studio --environment-rotation 180
# With the Khronos AlphaBlendModeTest model (glTF-Sample-Assets, CC-BY 4.0, by Ed Mackey,
# (c) 2018 Analytical Graphics, Inc.): bash app/docs/lighting/render.sh PATH/AlphaBlendModeTest.gltf
if [ $# -ge 1 ]; then
  "$bin" render "$1" -o "$out/alpha-blend-uniform.png" --width 384 --height 256 --spp 128 --seed 1 \
    --environment uniform
  "$bin" render "$1" -o "$out/alpha-blend-studio.png" --width 384 --height 256 --spp 128 --seed 1
fi
