#!/usr/bin/env bash
# Install the real engines demflow compares against (Debian packages), as root.
# Does nothing when both are already installed.
set -euo pipefail
if command -v yade >/dev/null && command -v liggghts >/dev/null; then
  exit 0
fi
if [ "$(id -u)" -ne 0 ]; then
  echo "install-engines.sh: run as root (it calls apt-get install -y yade liggghts)" >&2
  exit 1
fi
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq yade liggghts >/dev/null
yade --version | head -2 || true
