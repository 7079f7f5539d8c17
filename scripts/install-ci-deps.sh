#!/usr/bin/env bash
# Installs what CI needs beyond scripts/install-deps.sh, and only what is missing: Debian's
# AArch64 cross compiler, for the ARM compile check of `make check-widths`
# (scripts/check-widths.sh). Idempotent: a machine that has everything runs no apt-get at all.
set -euo pipefail

bash "$(dirname "$0")/install-deps.sh"

packages=(g++-aarch64-linux-gnu)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0

echo "seiche: installing missing packages: ${missing[*]}" >&2
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "seiche: need root (or sudo) to install: ${missing[*]}" >&2; exit 1; }
  SUDO="sudo"
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
