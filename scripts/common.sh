# Shared set-up for scripts/demo and scripts/test: system packages, configure, build.
# Sourced, not run. Idempotent: installs only what is missing, rebuilds only what changed.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build="$root/build"

# debian 12 packages talus builds against (README "Dependencies")
packages=(build-essential cmake pkg-config
  pocl-opencl-icd ocl-icd-opencl-dev opencl-headers opencl-clhpp-headers clinfo
  libeigen3-dev libembree-dev libsuitesparse-dev libgtest-dev libgmock-dev libbenchmark-dev
  nlohmann-json3-dev libcli11-dev libopenmpi-dev openmpi-bin libpng-dev libnlopt-dev libboost-dev libplplot-dev plplot-driver-cairo libcairo2-dev fonts-dejavu-core python3 python3-venv
  python3-dev pybind11-dev python3-numpy python3-pytest python3-matplotlib python3-vtk9
  git clang-format clang-tidy doxygen)

install_packages() {
  local missing=()
  for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  echo "talus: installing ${missing[*]}" >&2
  local sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
}

configure_and_build() {
  # warnings are errors in every build these scripts make, CI's and a person's alike: the same
  # flags, so switching between the two does not rebuild everything
  # compile_commands.json for scripts/lint's clang-tidy
  cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DTALUS_WERROR=ON \
    -DCMAKE_EXPORT_COMPILE_COMMANDS=ON >/dev/null
  cmake --build "$build" -j "$(nproc)"
}

# poCL's compiled-kernel cache lives in the build folder, so runs after the first skip LLVM
export POCL_CACHE_DIR="$build/pocl-cache"
mkdir -p "$POCL_CACHE_DIR"
# talus's settled piles too (terrain/pile_cache.hpp), so the demo's second run skips the settling
export TALUS_CACHE_DIR="$build/talus-cache"
