#!/usr/bin/env bash
# Install the Debian packages cdemblast needs (clang and its runtimes: the libFuzzer targets of
# make fuzz). Idempotent: does nothing when all are present.
# Must run as root (or with sudo available) on a Debian 12 machine. Needs only bash and apt: on a
# bare Debian 12 (minbase, no make) `bash scripts/install-deps.sh` is the first command.
#   --test   also the test-only group: VTK's and meshio's readers of the VTU/PVD outputs and
#            headless Chromium for the report's browser check (make test uses it, so CI runs
#            those checks instead of skipping them)
set -euo pipefail
WITH_TEST=0
for a in "$@"; do
  case "$a" in
    --test) WITH_TEST=1 ;;
    *) echo "install-deps: unknown option '$a' (expected --test)" >&2; exit 2 ;;
  esac
done
PKGS=(
  cmake ninja-build g++ make pkg-config
  libgmsh-dev libeigen3-dev libtoml11-dev libcli11-dev libspdlog-dev libfmt-dev zlib1g-dev
  libmetis-dev libopenmpi-dev openmpi-bin
  libgtest-dev libgmock-dev libbenchmark-dev
  python3 python3-matplotlib python3-numpy
  clang libclang-rt-14-dev
)
if [ "$WITH_TEST" -eq 1 ]; then
  PKGS+=(python3-vtk9 python3-meshio chromium fonts-dejavu-core)
fi
missing=()
for p in "${PKGS[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PKGS[@]} packages present"
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null; then SUDO="sudo"; else
    echo "install-deps: need root to install: ${missing[*]}" >&2; exit 1; fi
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
echo "install-deps: done"
