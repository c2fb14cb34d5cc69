#!/usr/bin/env bash
# Builds everything with clang-14 under AddressSanitizer + UndefinedBehaviorSanitizer and runs the
# ctest suite but for the long scenario tests listed below, whose paths shorter tests take here.
# Exits non-zero on any build failure, test failure or sanitizer report (UBSan is made fatal at
# compile time and at run time; ASan aborts and checks for leaks).
#
#   tests/run_sanitizers.sh [build_dir=<repo>/build-asan]
#   SANITIZE_ALL=1 tests/run_sanitizers.sh       # the whole suite
#
# clang-14 and its runtime are Debian packages (clang-14, libclang-rt-14-dev; llvm-14 puts
# llvm-symbolizer on the PATH, which turns a report's addresses into file:line). Line tables
# (-gline-tables-only) are all a report needs.
set -euo pipefail

REPO="$(cd "$(dirname "$0")/.." && pwd)"
BUILD_DIR="${1:-$REPO/build-asan}"
JOBS="${JOBS:-2}"
for tool in clang-14 clang++-14 llvm-symbolizer; do
    command -v "$tool" >/dev/null || {
        echo "run_sanitizers.sh: $tool not found; install clang-14 libclang-rt-14-dev llvm-14" >&2
        exit 1
    }
done

start=$(date +%s)
# BUILD_PYTHON=OFF: an ASan-instrumented extension module cannot be loaded into the (uninstrumented)
# Python interpreter without preloading the ASan runtime; the library code the module calls is
# covered here by the C++ suite.
cmake -S "$REPO" -B "$BUILD_DIR" -DCMAKE_C_COMPILER=clang-14 -DCMAKE_CXX_COMPILER=clang++-14 \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -gline-tables-only -DNDEBUG" \
    -DBUILD_BENCHMARKS=OFF -DBUILD_PYTHON=OFF \
    -DCMAKE_CXX_FLAGS="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined"
cmake --build "$BUILD_DIR" -j"$JOBS"
built=$(date +%s)

export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1"
export LSAN_OPTIONS="suppressions=$REPO/tests/lsan_suppressions.txt:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
# Scenario tests that repeat, on a longer walk or drive, code paths that shorter tests of this same
# run already take under the sanitizers (each name, then the test that takes its path here). They
# are 4-15x slower instrumented and half of this run's time; the ordinary build runs them all.
# SANITIZE_ALL=1 runs them here too.
excluded=(
    # the step-reading decision: EndToEndIndoor.HcuEightMeetsTheIndoorIssueFigures
    EndToEndIndoor.TheStepReadingIsDecidedPerWalk
    EndToEndIndoor.PdrStepsReadAboutTheirMedianKeepTheWalkOnTrack
    # the PCD/PLY/OctoMap readers: SynthBuilding.PcdPlyAndOctomapGiveTheSameField
    EndToEndIndoor.SyntheticBuildingSameResultFromPcdPlyOctomap
    SynthBuilding.SameSeedSameBytes
    # surface extraction: the WalkableSurface tests; a multi-floor correction:
    # EndToEndIndoor.LiftRideMisreadByTheBarometerEndsOnTheRightFloor
    CliMap.RawBuildingScanGivesTheWalkableSurfaceAndTheSameCorrection
    EndToEndIndoor.ADeclaredLiftOfASurfaceMapHoldsTheRide
    EndToEndIndoor.AWholeCorrectionOnAnotherFloorIsKeptWhenTheWalkExplainsItBetter
    EndToEndIndoor.LevelWalkingIsDrawnToAFloor
    EndToEndIndoor.TheFloorWhoseRidesReadAlikeIsKept
    # start-scale hypotheses and their covariance: EndToEndIndoor.HcuEightMeetsTheIndoorIssueFigures,
    # online: Online.TheCovarianceHoldsTheHypothesesOfCloseNll
    EndToEndIndoor.OnlineOutputFollowsTheStartScaleOfLowestNll
    EndToEndIndoor.StartsOfCloseNllWidenTheCovariance
    EndToEndIndoor.TheStartScaleOfLowestNllIsKept
    EndToEndIndoor.EachStartScaleIsAHypothesisItsWindowsKeep
    # relocalisation and the doubt bits: OnlineSynthetic.ASolveThatMovesTheChainRunsARelocalisation
    OnlineSynthetic.AChainInDoubtIsRelocalisedFromItsPrefix
    OnlineSynthetic.ASolveThatMovesTheChainOutsideItsRegionIsFlagged
    OnlineSynthetic.AChainInAWrongBasinFlagsItsOutputs
    Online.AWindowInAWrongBasinIsRestartedAndTheChainKeepsTheRoad
    # the online solves and their covariance: OnlineSynthetic.ThreadedSmoothedMatchesBatch,
    # OnlineSynthetic.BackPressureKeepsEveryOutputFresh
    OnlineSynthetic.TheCovarianceIsScaledByHowItHeldTheFinalEstimates
    OnlineSynthetic.FixedAndMarginalisedBoundariesBothCorrectTheOutput
    OnlineSynthetic.IntermediateSolvesMoveOnlyTheCausalOutput
    OnlineSynthetic.SynchronousMatchesBatch
    # monocular scale: Monocular.AGeneratedDriveOnAGridIsCorrected
    Monocular.TheStreamFindsTheScaleThenCorrects
)
listed="$(ctest --test-dir "$BUILD_DIR" -N)"
exclude_args=()
if [[ "${SANITIZE_ALL:-0}" != 1 ]]; then
    for name in "${excluded[@]}"; do
        # A renamed or removed test must leave this list too, or it would stop saying what runs.
        grep -qE "Test +#[0-9]+: ${name//./\\.}\$" <<<"$listed" || {
            echo "run_sanitizers.sh: no test named $name in $BUILD_DIR" >&2
            exit 1
        }
    done
    regex="$(IFS='|'; echo "^(${excluded[*]//./\\.})\$")"
    exclude_args=(-E "$regex")
    echo "not run under the sanitizers (SANITIZE_ALL=1 runs them): ${#excluded[@]} tests"
fi
status=0
ctest --test-dir "$BUILD_DIR" --output-on-failure -j"$JOBS" --timeout 1800 "${exclude_args[@]}" \
    || status=$?
end=$(date +%s)

echo "sanitizer build: $((built - start)) s, ctest: $((end - built)) s"
if [[ $status -ne 0 ]]; then
    echo "sanitizer run FAILED (ctest exit $status)"
    exit "$status"
fi
echo "sanitizer run passed"
