#!/usr/bin/env bash
# Build plait and run every check:
#   1. a Release tree (build/) with -Werror: ctest, then the example programs;
#   2. unless PLAIT_SKIP_SANITIZE=1, an ASan + UBSan tree (build-asan/, RelWithDebInfo): the same.
# Formatting differences are reported as a warning only. Exits non-zero on any failure.
#
# Environment: PLAIT_SKIP_SANITIZE=1 skips step 2; PLAIT_STABILITY_RUNS sets the random runs of
# the stability test in step 1 (its default, 300); PLAIT_SANITIZE_STABILITY_RUNS those of step 2
# (60: the sanitizer build is several times slower).
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
jobs=2 # the project's reference machine has 2 cores
start=$SECONDS
timings=()

step() { printf '\n==> %s\n' "$*"; }
elapsed() { printf '%dm%02ds' $(((SECONDS - $1) / 60)) $(((SECONDS - $1) % 60)); }

"$root/scripts/setup.sh"

# The CCD test reads the shared query data that sits beside the repository.
if [ ! -d "$root/../shared/ccd" ]; then
	echo "test: $(cd "$root/.." && pwd)/shared/ccd not found: the CCD test needs the shared data" \
		"folder beside the repository (../shared)" >&2
	exit 1
fi

# Formatting: a warning for now, while the code base is still being formatted.
if command -v clang-format >/dev/null 2>&1; then
	unformatted=()
	while IFS= read -r -d '' file; do
		clang-format --dry-run --Werror "$file" >/dev/null 2>&1 || unformatted+=("${file#./}")
	done < <(find src include tools tests bench examples -name '*.[ch]' -print0 2>/dev/null | sort -z)
	if [ ${#unformatted[@]} -gt 0 ]; then
		echo "test: warning: ${#unformatted[@]} file(s) differ from .clang-format (clang-format -i FILE):"
		printf '  %s\n' "${unformatted[@]}"
	fi
else
	echo "test: warning: clang-format not installed, formatting not checked"
fi

# The README's C example must be a verbatim part of examples/hello_cloth.c, which is compiled and run.
snippet=$(awk '/^```c$/ { inside = 1; next } inside && /^```$/ { exit } inside' README.md)
if [ -z "$snippet" ] || [[ "$(cat examples/hello_cloth.c)" != *"$snippet"* ]]; then
	echo "test: the C example in README.md is not a verbatim excerpt of examples/hello_cloth.c" >&2
	exit 1
fi

# Runs every example program of a build tree; they must exit 0.
run_examples() {
	local dir=$1 example log
	for example in "$dir"/examples/example_*; do
		log=$(mktemp)
		if ! "$example" >"$log" 2>&1; then
			cat "$log"
			rm -f "$log"
			echo "test: example $(basename "$example") failed" >&2
			return 1
		fi
		echo "$(basename "$example"): $(tail -n 1 "$log")"
		rm -f "$log"
	done
}

# ---- 1. Release, warnings as errors -----------------------------------------------------------
t=$SECONDS
step "Release build (build/, -Werror)"
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DPLAIT_WERROR=ON -DPLAIT_SANITIZE=OFF >/dev/null
cmake --build build -j"$jobs"
step "ctest (build/)"
(cd build && ctest --output-on-failure -j"$jobs")
step "examples (build/)"
run_examples build
timings+=("release build + tests + examples: $(elapsed "$t")")

# ---- 2. AddressSanitizer + UndefinedBehaviorSanitizer ------------------------------------------
if [ "${PLAIT_SKIP_SANITIZE:-0}" != 1 ]; then
	t=$SECONDS
	# RelWithDebInfo, not Debug: at -O0 under the sanitizers the stiffness test alone took 7.5 min
	# on two cores (1.5 min at -O2), and ASan and UBSan still see every access and operation.
	step "ASan + UBSan build (build-asan/, RelWithDebInfo)"
	cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPLAIT_SANITIZE=ON -DPLAIT_WERROR=ON >/dev/null
	cmake --build build-asan -j"$jobs"
	# fast_unwind_on_malloc=0: full allocation stacks, which scripts/lsan.supp needs (it costs ~20%).
	export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:fast_unwind_on_malloc=0
	export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
	export LSAN_OPTIONS=suppressions=$root/scripts/lsan.supp
	step "ctest (build-asan/)"
	(cd build-asan && PLAIT_STABILITY_RUNS=${PLAIT_SANITIZE_STABILITY_RUNS:-60} ctest --output-on-failure -j"$jobs")
	step "examples (build-asan/)"
	run_examples build-asan
	timings+=("sanitizer build + tests + examples: $(elapsed "$t")")
else
	timings+=("sanitizers: skipped (PLAIT_SKIP_SANITIZE=1)")
fi

step "all checks passed"
printf '  %s\n' "${timings[@]}" "total: $(elapsed "$start")"
