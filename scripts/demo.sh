#!/usr/bin/env bash
# Build plait (Release) and run the built-in demo: a cloth draping over a sphere onto the ground.
# Writes out/demo/ and says how to look at it.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"

"$root/scripts/setup.sh"

echo "==> building plait (build/, Release)"
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
# Only the command-line tool: the demo needs nothing else, and the tests take longer to compile.
cmake --build build -j2 --target plait_cli

echo "==> running the demo"
# Start from an empty folder so the listing below shows this run's files only.
rm -rf out/demo
build/tools/plait/plait run --out out/demo

objs=(out/demo/cloth.*.obj)
stats=out/demo/stats.jsonl
last=$(tail -n 1 "$stats")
# stats.jsonl has one flat JSON object per line; pull a number out of the last one.
field() { sed -n "s/.*\"$1\":\([^,}]*\).*/\1/p" <<<"$last"; }

cat <<EOT

Wrote $root/out/demo/:
  ${#objs[@]} OBJ meshes, ${objs[0]##*/} (the start) to ${objs[-1]##*/}, one per frame at 24 fps,
  and as many of the sphere and the ground (sphere.*.obj, ground.*.obj)
  stats.jsonl, one line of statistics per frame; manifest.json, what was written

Last frame: frame $(field frame), kinetic energy $(field kinetic_energy) J, max strain $(field max_strain),\
 penetrations $(field penetrations), contacts $(field contacts)

To look at it:
  - one frame in any mesh viewer, e.g. the end: out/demo/${objs[-1]##*/}
  - the animation in Blender: write a point cache as well,
      build/tools/plait/plait run --out out/demo --format pc2
    then File > Import > Wavefront (.obj) out/demo/cloth.obj, add a Mesh Cache modifier
    to it and open out/demo/cloth.pc2 (format PC2); scrub the timeline. Scenes are Y-up:
    if the cloth moves on its side, set the modifier's Up axis to +Y.
  - crossing triangles and vertices inside colliders, frame by frame:
      build/tools/plait/plait check out/demo
  - other scenes: build/tools/plait/plait run scenes/flag.json --out out/flag
EOT
