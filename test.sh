#!/usr/bin/env bash
# Every test: install what is missing, check the scripts (shellcheck) and the C++ form
# (clang-format), build with warnings as errors, run the test
# suite, then build and run it again under AddressSanitizer + UndefinedBehaviorSanitizer
# (clang; the same build gives the libFuzzer targets, run 10 s each at the end),
# and check that learner/ and problem/ build and pass alone, without OpenCV, LCM, CLI11
# or cpp-httplib (scripts/learner-only-check.sh). The benchmarks are built (so they keep
# compiling) but not run; see docs/BENCHMARKS.md.
set -euo pipefail
cd "$(dirname "$0")"
start=$(date +%s)
# One line per stage with the time so far: a run that is slow says where.
stage() { echo "== test.sh: $1 ($(($(date +%s) - start)) s so far)"; }
stage "installing what is missing"
scripts/install-deps.sh --for-tests
jobs="$(nproc)"

# The scripts a user runs and the tests' own: quoting (a path with a space once broke
# launch.sh), unused and unquoted variables. Every finding fails the run.
stage "shellcheck"
shellcheck services/launch.sh demo.sh test.sh .ci/run scripts/*.sh bench/*.sh tests/in_private_netns.sh \
  tests/services/netns_test.sh tests/dashboard/browser_test.sh
# The C++ form (.clang-format): every source as clang-format writes it.
stage "format"
scripts/format.sh --check

# Ninja when there is one: it compiles a library's sources while the libraries it links
# are still being built, and so keeps both cores busy (the Makefiles wait per target).
generator=()
if command -v ninja >/dev/null 2>&1; then generator=(-G Ninja); fi

stage "Release build"
# The demo's configuration (scripts/configure.sh), with the tests and benchmarks: what
# ./demo.sh built is not compiled again.
scripts/configure.sh build -DHBIRL_BUILD_TESTS=ON -DHBIRL_BUILD_BENCH=ON
cmake --build build -j"$jobs"
# Background builds take only what the tests leave idle (nice 19: the Release tests wait on
# timers and the network about a third of their time); a background job still running when
# this script exits, failing or interrupted, is stopped with it.
background() {  # background LOG COMMAND...: COMMAND at the lowest priority, output to LOG
  local log="$1"
  shift
  setsid nice -n 19 "$@" >"$log" 2>&1 &  # a process group of its own: stopped whole
}
stop_background() {
  local job
  for job in $(jobs -p); do kill -- -"$job" 2>/dev/null || true; done
}
trap stop_background EXIT
finish_background() {  # finish_background WHAT LOG: wait for the one background job
  local what="$1" log="$2" status=0
  wait -n || status=$?
  if [ "$status" -ne 0 ]; then
    tail -n 60 "$log" >&2
    echo "test.sh: $what failed (exit $status; the whole output: $log)" >&2
    exit 1
  fi
}

# -O1 with line tables only: half the compile time of -O2 -g, and still file:line in
# the sanitizers' reports. clang: the libraries also carry libFuzzer's coverage, so this
# one build serves the sanitizer tests and the fuzz targets (CMakeLists.txt says what it
# leaves out); it took 432 s where gcc's sanitizer build and a separate fuzz build took
# 835 s. Ninja when there is one (above). Compiled while the Release tests run.
CC=clang CXX=clang++ cmake -S . -B build-sanitize-fuzz "${generator[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
      -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" -DHBIRL_WERROR=ON -DHBIRL_SANITIZE=ON -DHBIRL_BUILD_BENCH=OFF >/dev/null
# What the sanitizer run needs: the test executable, the hbirl command it runs, the
# bindings it compiles; and the fuzz targets.
background build-sanitize-fuzz/build.log \
  cmake --build build-sanitize-fuzz -j"$jobs" --target hbirl_tests hbirl hbirl_lcmtypes_bindings hbirl_fuzz
stage "Release tests (the sanitizer and fuzz build (clang) in the background)"
ctest --test-dir build --output-on-failure -j"$jobs"
stage "sanitizer and fuzz build: what is left of it"
finish_background "the sanitizer and fuzz build" build-sanitize-fuzz/build.log

# Run in the Release build only: the multi-process tests (label multiprocess: whole
# service sets over LCM in network namespaces; the same service code runs under the
# sanitizers in the in-process tests), twenty-seven statistics-heavy tests that take
# seconds in Release and up to two minutes each under the sanitizers (the E-step, EM and the
# experiment runners they drive run under the sanitizers in the other tests), and one that
# compares CPU times (the reader it times is fuzzed under the sanitizers).
heavy='^(EtaSensitivity\.LearnedEtaFindsTheCalibrationAndSameBitsForAnyThreads|LearnReward\.RecordedObjectiveNeverDecreasesOnRandomTasks|Cli\.EtaExperimentsAtSmallScale|Unlisted\.MethodsRunAndTheOracleIsToldEverything|HiddenDataEm\.AccelerationConvergesFasterToNoWorseLikelihood|HiddenDataEm\.GridworldWithThreeConfoundersAndPlausibleEtaRecoversTheGoal|RandomTasks\.DefaultIsRightAtLeastAsOftenAsTheFixedPrior|Cli\.GridworldExperimentAtSmallScale|OnionData\.QualitiesAlternate|Pipeline\.GridworldOfSizeTenLearnsTheGoal|ObservationEStep\.LearnedEtaRecoversTheLabellersCalibration|Cli\.EveryGeneratedRandomTaskValidates|Cli\.OnionExperimentAtSmallScale|LearnAnytime\.EachEstimateIsLearnOnThePrefixFromThePreviousAndNoWorseThanFresh|StoppingExperiment\.AnEstimatePerDemonstration|CalibrationExperiment\.RunsAndReadsBack|RewardPosterior\.OneFeatureFromObservationsAgreesWithEnumerationOnAGrid|JudgedTasks\.StoppingOnTheGridworld|JudgedTasks\.TasksOfTheFigures|CalibrationExperiment\.OnTheGridworldFiguresRuns|Learn\.IsTheLearnersPartsBitForBit|Cli\.AnytimeEstimatesAreReproducedOneByOne|RandomTasks\.EmStartedAtTheTruthStartsThere|ProblemFile\.ReadingIsLinearInATrajectorysLength|RandomTasks\.EachDiagnosticOfTheSubjectsOChangesTheAnswer|RandomTask\.DrawsStayInTheirRanges|RewardPosterior\.TwoFeaturesFromTrueTrajectoriesAgreeWithAGrid|Learn\.DrawsThePosteriorWhenAsked)$'
# The learner-only check builds in the background meanwhile.
mkdir -p build-learner-only
# (Without the heavy tests: what it checks is that the maths builds and runs alone; the
# Release build ran them.)
background build-learner-only/check.log scripts/learner-only-check.sh build-learner-only "$jobs" -E "$heavy"
stage "sanitizer tests (the learner-only build and tests in the background)"
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir build-sanitize-fuzz --output-on-failure -j"$jobs" -LE multiprocess -E "$heavy"
stage "learner-only build and tests: what is left of them"
finish_background "the learner-only check" build-learner-only/check.log
grep -E "^learner-only:|tests passed" build-learner-only/check.log

# libFuzzer (clang, ASan + UBSan): every reader of files and of the bus, and the
# dashboard's HTTP handling, 10 s each on its seed corpus (tests/fuzz; the long runs are
# in tests/fuzz/RESULTS.md). Fails on any crash, leak, timeout or huge allocation.
stage "fuzz targets"
scripts/fuzz.sh build-sanitize-fuzz 10
stage "all passed"
