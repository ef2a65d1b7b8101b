#!/usr/bin/env bash
# Usage: bench/pinocchio/build.sh [all|generic|native]
# Build the Pinocchio peer benchmark against the headers and libraries shipped by the `pin` wheel
# (site-packages/cmeel.prefix). Produces two binaries in bench/pinocchio/build/:
#   bench_pinocchio         -O3 -DNDEBUG (generic x86-64, like the wheel)
#   bench_pinocchio_native  -O3 -DNDEBUG -march=native (+ Eigen ABI pinning, see below)
# Requirements: python3 with `pin` (Pinocchio 4.1), g++ with C++17. Missing header packages
# (cmeel-eigen, cmeel-urdfdom-headers) are pip-installed into the same prefix.
# Environment overrides: CXX (default g++), PYTHON (default python3), CMEEL_PREFIX.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
out="$here/build"
CXX="${CXX:-g++}"
PYTHON="${PYTHON:-python3}"

if [[ -z "${CMEEL_PREFIX:-}" ]]; then
  CMEEL_PREFIX="$("$PYTHON" -c 'import cmeel, os; print(os.path.join(os.path.dirname(cmeel.__path__[0]), "cmeel.prefix"))')"
fi
prefix="$CMEEL_PREFIX"
[[ -f "$prefix/include/pinocchio/config.hpp" ]] || { echo "no Pinocchio headers in $prefix (pip install pin)" >&2; exit 1; }
[[ -d "$prefix/include/boost" ]] || { echo "no Boost headers in $prefix (pip install cmeel-boost)" >&2; exit 1; }
if [[ ! -d "$prefix/include/eigen3/Eigen" ]]; then
  echo "Eigen headers missing in $prefix: installing cmeel-eigen" >&2
  "$PYTHON" -m pip install --quiet cmeel-eigen
fi
[[ -d "$prefix/include/eigen3/Eigen" ]] || { echo "no Eigen headers in $prefix" >&2; exit 1; }
# The URDF parser header includes urdfdom's model headers (Pinocchio 4.1 was built against 3.0).
if [[ ! -f "$prefix/include/urdfdom_headers/urdf_model/model.h" ]]; then
  echo "urdfdom headers missing in $prefix: installing cmeel-urdfdom-headers==3.0.0" >&2
  "$PYTHON" -m pip install --quiet "cmeel-urdfdom-headers==3.0.0"
fi
[[ -f "$prefix/include/urdfdom_headers/urdf_model/model.h" ]] || { echo "no urdfdom headers in $prefix" >&2; exit 1; }

mkdir -p "$out"

# Same preprocessor definitions as the wheel's pinocchio CMake targets: the Boost.MPL limits
# change the joint variant type, so they must match the compiled library.
defs=(
  -DBOOST_MPL_LIMIT_LIST_SIZE=30
  -DBOOST_MPL_LIMIT_VECTOR_SIZE=30
  -DBOOST_MPL_CFG_NO_PREPROCESSED_HEADERS
  -DBOOST_FUSION_INVOKE_MAX_ARITY=12
  -DPINOCCHIO_WITH_URDFDOM
  -DPINOCCHIO_URDFDOM_HEADERS_MAJOR_VERSION=3
  -DPINOCCHIO_URDFDOM_HEADERS_MINOR_VERSION=0
  -DPINOCCHIO_URDFDOM_HEADERS_PATCH_VERSION=0
)
# PINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION is deliberately NOT defined: the algorithms are compiled
# from the headers in this translation unit with the flags below (header-only use, as Pinocchio's
# own benchmarks do), so -march=native really applies to them. The shared libraries provide the
# URDF/MJCF parsing support only.
incs=(-I"$prefix/include" -I"$prefix/include/eigen3" -I"$prefix/include/urdfdom_headers"
      -I"$prefix/include/urdfdom")
libs=(-L"$prefix/lib" -Wl,-rpath,"$prefix/lib"
      -lpinocchio_parsers -lpinocchio_default -lurdfdom_model -ltinyxml2 -lconsole_bridge
      -lboost_filesystem -lboost_serialization -lpthread)

build() {
  local name="$1"; shift
  local flags="$*"
  echo "building $out/$name with: $flags" >&2
  # shellcheck disable=SC2086
  "$CXX" $flags -Wno-deprecated-declarations "${defs[@]}" "${incs[@]}" -DBENCH_COMPILER_FLAGS="\"$CXX $flags\"" \
    "$here/bench.cpp" -o "$out/$name" "${libs[@]}"
}

which="${1:-all}"   # all | generic | native
# Generic build: default Eigen alignment (16 bytes), identical to the wheel's libraries.
if [[ "$which" == all || "$which" == generic ]]; then
  build bench_pinocchio -O3 -DNDEBUG -std=c++17
fi
# Native build: the wheel's libraries (which build the Model) use Eigen's SSE2 defaults, i.e.
# 16-byte alignment and plain malloc/free for heap arrays. With AVX/AVX-512 Eigen would raise the
# alignment to 32/64 bytes (different object layout) and switch to its own aligned allocator
# (freeing malloc'ed arrays with it crashes in ~Model). EIGEN_MAX_ALIGN_BYTES=16 keeps the layout,
# EIGEN_MALLOC_ALREADY_ALIGNED=1 keeps malloc/free; vector instructions still use the native ISA.
if [[ "$which" == all || "$which" == native ]]; then
  build bench_pinocchio_native -O3 -DNDEBUG -std=c++17 -march=native -DEIGEN_MAX_ALIGN_BYTES=16 \
    -DEIGEN_MALLOC_ALREADY_ALIGNED=1
fi
echo "done: $(ls "$out")" >&2
