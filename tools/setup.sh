#!/usr/bin/env bash
# Installs what is missing (Debian packages, the venv, pip packages) and builds the
# catkin workspace in .ws/. Idempotent: a second run installs and rebuilds nothing new.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
say() { printf '[setup] %s\n' "$*"; }

# 1. Debian packages (ROS 1 from Debian's own archive).
sudo_cmd=()
[ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
mapfile -t wanted < <(grep -vE '^\s*(#|$)' tools/debian-packages.txt)
missing=()
for p in "${wanted[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  say "installing ${#missing[@]} Debian packages: ${missing[*]}"
  # env: sudo drops DEBIAN_FRONTEND; the lock timeout waits out another set-up's apt-get
  apt=("${sudo_cmd[@]}" env DEBIAN_FRONTEND=noninteractive apt-get -o DPkg::Lock::Timeout=600)
  "${apt[@]}" update -q
  "${apt[@]}" install -y -q --no-install-recommends "${missing[@]}"
else
  say "Debian packages: all ${#wanted[@]} present"
fi

# 2. The venv: Debian's python (the one rospy is built for) with system site-packages; one
#    made otherwise (another python on PATH, no system site-packages) has no rospy: remade.
if [ -x .venv/bin/python ] && ! { grep -qx 'home = /usr/bin' .venv/pyvenv.cfg \
    && grep -qx 'include-system-site-packages = true' .venv/pyvenv.cfg; } 2>/dev/null; then
  say "remaking .venv: it was not made from /usr/bin/python3 with system site-packages"
  rm -rf .venv
fi
if [ ! -x .venv/bin/python ]; then
  say "creating .venv from /usr/bin/python3"
  /usr/bin/python3 -m venv --system-site-packages .venv
fi
# tools/requirements.txt resolves normally; tools/requirements-camera.txt (MediaPipe for the
# camera sources) is fully pinned and installed with --no-deps: mediapipe declares jax,
# jaxlib and more that its Hands solution never imports.
req_hash=$(cat tools/requirements.txt tools/requirements-camera.txt | sha256sum | cut -d' ' -f1)
if [ "$(cat .venv/.requirements.sha256 2>/dev/null)" != "$req_hash" ]; then
  say "installing pinned pip packages (tools/requirements.txt, tools/requirements-camera.txt) into .venv"
  # pip's own status decides (the grep only hides a harmless line): a pin that failed to
  # install must not be marked as installed
  pip_install() {
    .venv/bin/python -m pip install -q --disable-pip-version-check "$@" 2>&1 \
      | { grep -v "is ignored: it is neither a file nor a directory" || true; }
    return "${PIPESTATUS[0]}"
  }
  pip_install -r tools/requirements.txt \
    || { echo "[setup] pip install of tools/requirements.txt failed (see above)" >&2; exit 1; }
  pip_install --no-deps -r tools/requirements-camera.txt \
    || { echo "[setup] pip install of tools/requirements-camera.txt failed (see above)" >&2; exit 1; }
  .venv/bin/python -c "import pybullet, numpy, lzstring, yaml, hypothesis, pytest, sklearn, mediapipe, cv2" \
    >/dev/null 2>&1 || { echo "[setup] the pip packages do not import (see above)" >&2; exit 1; }
  echo "$req_hash" > .venv/.requirements.sha256
else
  say "pip packages: up to date"
fi

# 3. The loopback bind() shim that env.sh preloads while ROS_IP / ROS_HOSTNAME is loopback
#    (roscpp nodes would otherwise listen on every interface; see tools/loopback_bind.c).
mkdir -p .ws
if [ ! -f .ws/loopback_bind.so ] || [ tools/loopback_bind.c -nt .ws/loopback_bind.so ]; then
  if command -v cc >/dev/null 2>&1; then
    say "building the loopback bind() shim (.ws/loopback_bind.so)"
    cc -shared -fPIC -O2 -Wall -o .ws/loopback_bind.so.tmp tools/loopback_bind.c -ldl \
      && mv .ws/loopback_bind.so.tmp .ws/loopback_bind.so
  else
    say "WARNING: no C compiler: roscpp nodes will listen on all interfaces (see docs/reliability.md, Network)"
  fi
fi

# 4. Out-of-tree catkin workspace. .ws/src/leap_teleop mirrors this repository with one
#    link per top-level entry that git tracks or would track (so not .ws itself, .venv,
#    .git or generated output such as demo_output/): a link to the whole repository put the
#    workspace inside its own package, where rosrun's `find -L` met every script several
#    times and asked which one to run.
say "building the catkin workspace in .ws/"
(
  set +u
  source /opt/ros/*/setup.bash 2>/dev/null || true
  exec 9>.ws/.build.lock
  flock 9   # concurrent set-ups (parallel shells, helpers) build one at a time
  pkg=.ws/src/leap_teleop
  if [ -L "$pkg" ]; then rm "$pkg"; fi      # the earlier layout: one link to the repository
  mkdir -p "$pkg"
  if ! entries=$(git -C "$root" ls-files --cached --others --exclude-standard 2>/dev/null \
                 | cut -d/ -f1 | sort -u | grep -v '^\.'); then
    entries=$(cd "$root" && ls)               # not a git checkout: every visible entry
  fi
  for name in $entries; do
    [ "$(readlink "$pkg/$name")" = "$root/$name" ] || ln -sfn "$root/$name" "$pkg/$name"
  done
  for link in "$pkg"/*; do                  # entries gone from (or ignored by) the repository
    name=$(basename "$link")
    if [ -L "$link" ] && ! grep -qx -- "$name" <<<"$entries"; then rm "$link"; fi
  done
  cd .ws
  # The venv's python is Debian's /usr/bin/python3 plus the pip packages: node wrappers
  # that catkin generates then start inside the venv wherever they are launched from.
  catkin_make -DPYTHON_EXECUTABLE="$root/.venv/bin/python3" -DCATKIN_ENABLE_TESTING=ON \
    > build.log 2>&1 || { tail -40 build.log; echo "[setup] catkin_make failed; full log in .ws/build.log" >&2; exit 1; }
)
say "ready: run commands with ./env.sh CMD, or 'source env.sh'"
