#!/usr/bin/env bash
# Run here, in the project root, before lending a GPU machine its one run (see benchmarks/gpu/README.md).
# Fills .whl/ (ignored by git) with what that offline machine lacks, for its Python 3.12:
#   - the wheels clrender needs that its image does not hold (pyopencl and its pure-Python needs, trimesh, OpenEXR);
#   - mi.tar.xz: Mitsuba 3 + Dr.Jit unpacked, cut down to the cuda_ad_rgb and scalar_rgb variants and the
#     plugins our twin scenes can use, so that everything fits the 64 MiB a run may carry (the wheels are 67 MB).
set -euo pipefail
MITSUBA=${MITSUBA:-3.9.1}
grep -qx '/.whl/' .git/info/exclude 2>/dev/null || echo '/.whl/' >> .git/info/exclude
rm -rf .whl && mkdir -p .whl
pip_dl() {
  python3 -m pip download -q --no-deps --only-binary=:all: --python-version 3.12 --implementation cp \
    --platform manylinux_2_28_x86_64 --platform manylinux_2_27_x86_64 --platform manylinux_2_17_x86_64 \
    --platform manylinux2014_x86_64 -d "$@"
}
pip_dl .whl pyopencl pytools platformdirs siphash24 trimesh OpenEXR
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
pip_dl "$tmp" "mitsuba==$MITSUBA"
drjit=$(unzip -p "$tmp"/mitsuba-*.whl '*/METADATA' | sed -n 's/^Requires-Dist: drjit==\([0-9.]*\).*/\1/p')
pip_dl "$tmp" "drjit==$drjit"
mkdir "$tmp/site"
for w in "$tmp"/*.whl; do unzip -q -o "$w" -d "$tmp/site"; done
(
  cd "$tmp/site"
  rm -rf mitsuba/include mitsuba/mitsuba_stubs mitsuba/cmake drjit/include
  find . -name '*.pyi' -delete
  # one GPU variant (and scalar_rgb, which Mitsuba's own Python code may import)
  find mitsuba -maxdepth 1 -name '*.cpython-*.so' \
    ! -name 'cuda_ad_rgb.*' ! -name 'scalar_rgb.*' ! -name 'mitsuba_ext.*' ! -name 'mitsuba_alias.*' -delete
  # plugins no twin scene names (each holds every variant's code)
  for p in sunsky timed_sunsky sdfgrid bsplinecurve linearcurve ellipsoids ellipsoidsmesh volpath volpathmis ptracer; do
    rm -f "mitsuba/plugins/$p.so"
  done
)
tar -C "$tmp/site" -cf - . | xz -6 -T0 > .whl/mi.tar.xz
du -sh .whl; ls -la .whl
