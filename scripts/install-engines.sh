#!/usr/bin/env bash
# Install what the live tests need (Debian packages), as root: the real engines demflow compares
# against (yade, liggghts) and headless Chromium for the report test (chromium-headless-shell).
# Does nothing when all are already installed.
set -euo pipefail
if command -v yade >/dev/null && command -v liggghts >/dev/null \
   && { command -v chromium-headless-shell >/dev/null || command -v chromium >/dev/null; }; then
  exit 0
fi
if [ "$(id -u)" -ne 0 ]; then
  echo "install-engines.sh: run as root (it calls apt-get install -y yade liggghts chromium-headless-shell)" >&2
  exit 1
fi
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq yade liggghts chromium-headless-shell >/dev/null
yade --version | head -2 || true
