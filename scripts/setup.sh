#!/usr/bin/env bash
# Make sure the Debian packages plait needs to build and test are installed.
# As root: installs the missing ones. Otherwise: prints the apt-get line and exits 1.
# Silent when everything is already there, so the other scripts can call it every time.
set -euo pipefail

packages=(
	build-essential   # gcc, make, libc headers
	cmake             # >= 3.22
	pkg-config        # finds jansson, assimp, criterion; used by plait.pc users too
	libjansson-dev    # scene files (tool)
	libassimp-dev     # mesh files (tool)
	libcriterion-dev  # the test suite
	assimp-testmodels # broken-file corpus for a tool test (skipped when absent)
)
if ! command -v dpkg-query >/dev/null 2>&1; then
	echo "setup: dpkg not found (not Debian/Ubuntu?); make sure these or their equivalents are installed:" >&2
	echo "  ${packages[*]}" >&2
	exit 0
fi

missing=()
for p in "${packages[@]}"; do
	# dpkg -s succeeds for removed-but-configured packages too; look at the status itself.
	if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
		missing+=("$p")
	fi
done
[ ${#missing[@]} -eq 0 ] && exit 0

if [ "$(id -u)" -ne 0 ]; then
	echo "setup: missing Debian packages: ${missing[*]}" >&2
	echo "setup: install them with:" >&2
	echo "  sudo apt-get update && sudo apt-get install -y --no-install-recommends ${missing[*]}"
	exit 1
fi

echo "setup: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
# </dev/null: never wait for an answer (CI has no stdin).
apt-get update -qq </dev/null
apt-get install -y -qq --no-install-recommends "${missing[@]}" </dev/null
