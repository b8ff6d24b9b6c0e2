#!/usr/bin/env bash
# Measures the viewer as a user runs it, under Xvfb with software rendering (lavapipe), and
# writes app/docs/viewer/figures.md (README links it). Per
# integrator on the Cornell box with a glass sphere, at 640 x 480 and 1280 x 720, in a
# 1280 x 800 window with the plots shown and fresh settings:
#   - the time from the scene's load to its first image (and from launch), and from launch
#     to the first pass;
#   - UI frames per second while the render's progress alone redraws the window (paced),
#     and while it redraws continuously, as when the user drags a slider (--animate): the
#     mean from the first image to the screenshot;
#   - the UI's share of the CPU while progress alone redraws: the CPU time of the viewer's
#     threads other than the render's (the UI thread, lavapipe's rasteriser threads), from
#     the first pass to the screenshot, over both cores (the X server's copy of each frame,
#     another process, is not counted: about a fifth of that again, measured per process);
#   - render throughput with the viewer open (paced) against the headless command, both in
#     their steady state, from the first pass on (`--stats`' steady_samples_per_second).
# Usage (about 10 minutes): bash app/docs/viewer/measure.sh
set -euo pipefail
cd "$(dirname "$0")/../../.."
cargo build --release -q
bin=target/release/caustica
work=$(mktemp -d)
trap 'kill $xvfb 2>/dev/null || true; rm -rf "$work"' EXIT
display=:$((70 + $$ % 20))
Xvfb "$display" -screen 0 1600x1000x24 -nolisten tcp >/dev/null 2>&1 &
xvfb=$!
sleep 1
mkdir -p "$work/xdg" && chmod 700 "$work/xdg"
seconds=10

# The number after "key": in a flat JSON record.
field() { grep -o "\"$2\":[^,}]*" "$1" | head -1 | cut -d: -f2; }

viewer() { # integrator width height extra-flags... -> the JSON record's path
  local out="$work/$1-$2x$3${4:-}.png"
  rm -rf "$work/home"
  DISPLAY=$display XDG_RUNTIME_DIR=$work/xdg HOME=$work/home XDG_DATA_HOME=$work/home/data \
    timeout 300 "$bin" assets/cornell-glass.gltf --integrator "$1" --width "$2" --height "$3" \
    --window-size 1280x800 --screenshot "$out" --screenshot-after "$seconds" ${4:-} \
    >/dev/null 2>&1
  echo "${out%.png}.json"
}

# The headless command's steady rate (from its first pass on, as the viewer's).
headless_rate() { # integrator width height seconds -> samples per second
  "$bin" render assets/cornell-glass.gltf -o "$work/h.exr" --integrator "$1" --width "$2" \
    --height "$3" --time "$4" --stats "$work/h.json" >/dev/null 2>&1
  field "$work/h.json" steady_samples_per_second
}

# A first launch after a build reads the binary and the drivers from disk: warm them up.
viewer pt 320 240 >/dev/null

table="| integrator | size | first image after load (after launch) | first pass | UI frames/s paced | UI frames/s redrawing | UI share of the CPU, paced | render samples/s, viewer / headless |
| --- | --- | --- | --- | --- | --- | --- | --- |"
for integrator in pt bdpt mmlt ppm sppm pppm; do
  for size in "640 480" "1280 720"; do
    set -- $size
    paced=$(viewer "$integrator" "$1" "$2")
    animated=$(viewer "$integrator" "$1" "$2" --animate)
    h_rate=$(headless_rate "$integrator" "$1" "$2" $((seconds + 2)) | awk '{ printf "%.3g", $1 }')
    v_rate=$(field "$paced" steady_samples_per_second | awk '{ printf "%.3g", $1 }')
    ratio=$(awk -v v="$v_rate" -v h="$h_rate" 'BEGIN { printf "%.2f", v / h }')
    first_pass=$(field "$paced" first_pass_seconds)
    [ "$first_pass" = null ] && first_pass="> ${seconds}" || first_pass=$(printf "%.2f" "$first_pass")
    loaded=$(field "$paced" scene_loaded_seconds)
    first=$(field "$paced" first_frame_seconds)
    after_load=$(awk -v f="$first" -v l="$loaded" 'BEGIN { printf "%.2f", f - l }')
    share=$(field "$paced" ui_cpu_share | awk '{ printf "%.1f %%", 100 * $1 }')
    row=$(printf "| %s | %s x %s | %s s (%.2f s) | %s s | %.1f | %.1f | %s | %s / %s (%s) |" \
      "$integrator" "$1" "$2" "$after_load" "$first" "$first_pass" "$(field "$paced" ui_fps)" \
      "$(field "$animated" ui_fps)" "$share" "$v_rate" "$h_rate" "$ratio")
    table="$table
$row"
    echo "$row"
  done
done

{
  echo "Measured by \`bash app/docs/viewer/measure.sh\` on $(nproc) cores, $(date -u +%Y-%m-%d)."
  echo
  echo "$table"
} > app/docs/viewer/figures.md
