#!/usr/bin/env bash
# One-time set-up on a fresh machine: Python 3.12 venv with uv, the project (editable) and its test
# tools, and FFmpeg's shared libraries for LeRobot's video decoder. Safe to re-run.
set -euo pipefail
cd "$(dirname "$0")/.."

# Python 3.12: pyenv reads .python-version (holding 3.12) in this folder.
PYTHON=${PYTHON:-python}
if ! "$PYTHON" -c 'import sys; assert sys.version_info[:2] == (3, 12)' 2>/dev/null; then
  if command -v pyenv >/dev/null && pyenv root >/dev/null 2>&1; then
    PYTHON=$(ls -d "$(pyenv root)"/versions/3.12*/bin/python 2>/dev/null | tail -n 1)
  fi
fi
"$PYTHON" -c 'import sys; assert sys.version_info[:2] == (3, 12), sys.version' || {
  echo "Python 3.12 is required (LeRobot 0.6 needs it); set PYTHON=/path/to/python3.12" >&2; exit 1; }

"$PYTHON" -m uv --version >/dev/null 2>&1 || "$PYTHON" -m pip install --quiet uv
export UV_PYTHON_DOWNLOADS=never  # uv must use this interpreter, it cannot download one
[ -x .venv/bin/python ] || "$PYTHON" -m uv venv --quiet .venv -p "$PYTHON"
"$PYTHON" -m uv pip install --quiet -p .venv/bin/python -e ".[dev]"
# This venv writes bytecode even where PYTHONDONTWRITEBYTECODE is set (some machines set it): without it every
# process would compile torch, transformers and LeRobot from source again (~10 s per import of LeRobot). Each
# module is compiled at its first import, so only what runs is compiled: compiling all of site-packages up front
# (uv's --compile-bytecode) took ~85 s of CPU, most of it for modules nothing here imports.
SITE=$(.venv/bin/python -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
echo "import sys; sys.dont_write_bytecode = False" > "$SITE/_factorworld_write_bytecode.pth"

# FFmpeg shared libraries let torchcodec load (otherwise every process prints a long traceback).
if ! ldconfig -p 2>/dev/null | grep -q libavcodec; then
  if command -v apt-get >/dev/null && [ "$(id -u)" = 0 ]; then
    (apt-get update -qq && apt-get install -y -qq ffmpeg >/dev/null) || echo "warning: could not install ffmpeg" >&2
  else
    echo "note: install FFmpeg's shared libraries (e.g. apt-get install ffmpeg) for torchcodec" >&2
  fi
fi
# Chromium for the test that opens report.html in a real browser (Playwright drives it; its own download
# cannot work offline).
if ! command -v chromium >/dev/null; then
  if command -v apt-get >/dev/null && [ "$(id -u)" = 0 ]; then
    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null) \
      || echo "warning: could not install chromium (the report's browser test will be skipped)" >&2
  else
    echo "note: install Chromium (e.g. apt-get install chromium) for the report's browser test" >&2
  fi
fi
echo "set-up done: $(.venv/bin/python --version), $(.venv/bin/factorworld --help >/dev/null && echo factorworld CLI ok)"
