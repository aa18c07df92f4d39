#!/usr/bin/env bash
# The GPU checks of `irid export` and its shaders (docs/gpu.md): installs a
# software Vulkan driver (Mesa's lavapipe) and glslang when missing, then
# runs the irid-gpu crate's tests with IRID_REQUIRE_GPU=1, so that a missing
# Vulkan adapter fails instead of skipping. Idempotent; run as root on
# Debian (apt-get) or with the packages already installed.
set -euo pipefail
cd "$(dirname "$0")/../.."

missing=()
[ -e /usr/share/vulkan/icd.d/lvp_icd.x86_64.json ] || ls /usr/share/vulkan/icd.d/lvp_icd.*.json >/dev/null 2>&1 || missing+=(mesa-vulkan-drivers)
command -v glslangValidator >/dev/null 2>&1 || missing+=(glslang-tools)
if [ ${#missing[@]} -gt 0 ]; then
    echo "== installing ${missing[*]}"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >/dev/null
fi

echo "== irid-gpu tests (wgpu on Vulkan; IRID_REQUIRE_GPU=1)"
IRID_REQUIRE_GPU=1 cargo test --release -p irid-gpu -- --nocapture
