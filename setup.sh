#!/usr/bin/env bash
# One-command set-up for a fresh Debian 12 machine (run as root):
#   bash setup.sh demo   installs what is missing, builds, corrects the default (synthetic) scenario
#   bash setup.sh test   installs what is missing, builds, runs the whole test suite
#   bash setup.sh packages   prints the Debian packages it installs, one a line
# Everything comes from Debian packages; nothing is downloaded at configure or build time.
set -euo pipefail
cd "$(dirname "$0")"

mode=${1:-demo}
build_dir=${BUILD_DIR:-build}
packages=(build-essential cmake pkg-config libeigen3-dev coinor-libipopt-dev liblapack-dev
          libblas-dev libyaml-cpp-dev libgeographiclib-dev libproj-dev libexpat1-dev
          libgtest-dev libbenchmark-dev libpcl-dev liboctomap-dev nlohmann-json3-dev
          libosmium2-dev libprotozero-dev zlib1g-dev librsvg2-dev python3-dev pybind11-dev python3-numpy
          python3-pytest python3-distributed)

install_missing() {
    local missing=()
    for p in "${packages[@]}"; do
        dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
    done
    if [ ${#missing[@]} -gt 0 ]; then
        echo "[setup] installing: ${missing[*]}"
        export DEBIAN_FRONTEND=noninteractive
        apt-get update -q
        apt-get install -y -q --no-install-recommends "${missing[@]}"
    fi
}

build() {
    cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release
    cmake --build "$build_dir" -j "$(nproc)"
}

case "$mode" in
    packages)
        printf '%s\n' "${packages[@]}"
        ;;
    demo)
        install_missing
        build
        scenario="$build_dir/scenarios/synthetic-road"
        "$build_dir/datasets/driftcorr_make_road_scenario" "$scenario"
        "$build_dir/examples/driftcorr" correct "$scenario" -o "$build_dir/corrected.tum" \
            --geojson "$build_dir/corrected.geojson"
        ;;
    test)
        install_missing
        build
        (cd "$build_dir" && ctest --output-on-failure -j "$(nproc)")
        ;;
    *)
        echo "usage: bash setup.sh [demo|test|packages]" >&2
        exit 1
        ;;
esac
