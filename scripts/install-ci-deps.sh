#!/usr/bin/env bash
# Installs what CI needs, and only what is missing: what Seiche builds with
# (scripts/install-deps.sh), Debian's AArch64 cross compiler, for the ARM compile check of
# `make check-widths` (scripts/check-widths.sh), and clang 14 with its sanitizer and libFuzzer
# runtimes, for `make fuzz`. Idempotent: a machine that has everything runs no apt-get at all.
set -euo pipefail
exec bash "$(dirname "$0")/install-deps.sh" g++-aarch64-linux-gnu clang-14 libclang-rt-14-dev
