#!/usr/bin/env bash
# The project's environment: the venv first on PATH, the catkin workspace sourced,
# ROS bound to loopback unless you set ROS_IP / ROS_HOSTNAME yourself.
#   ./env.sh CMD ARGS...   run CMD inside it
#   source env.sh          set it up in this shell
_lt_root=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
if [ ! -f "$_lt_root/.ws/devel/setup.bash" ] || [ ! -x "$_lt_root/.venv/bin/python" ]; then
  echo "leap_teleop: not set up yet; run 'make setup' (or make demo / make test) first" >&2
  # shellcheck disable=SC2317
  return 1 2>/dev/null || exit 1
fi
set +u
_lt_args=("$@")
set --     # catkin's setup.bash reads its own options from the positional arguments
# shellcheck disable=SC1091
source "$_lt_root/.ws/devel/setup.bash"
# shellcheck disable=SC1091
source "$_lt_root/.venv/bin/activate"
export ROS_HOSTNAME=${ROS_HOSTNAME:-127.0.0.1}
export ROS_IP=${ROS_IP:-127.0.0.1}
export ROS_MASTER_URI=${ROS_MASTER_URI:-http://127.0.0.1:11311}
export ROS_HOME=${ROS_HOME:-$_lt_root/.ws/ros_home}
# roscpp nodes listen on 0.0.0.0 whatever ROS_IP says: while ROS is on loopback, preload
# the shim that turns their wildcard binds into loopback ones (tools/loopback_bind.c).
case "${ROS_HOSTNAME:-$ROS_IP}" in
  127.*|localhost|::1)
    if [ -f "$_lt_root/.ws/loopback_bind.so" ] && [[ ":${LD_PRELOAD:-}:" != *":$_lt_root/.ws/loopback_bind.so:"* ]]; then
      export LD_PRELOAD="$_lt_root/.ws/loopback_bind.so${LD_PRELOAD:+:$LD_PRELOAD}"
    fi ;;
esac
# Python's own default: compiled modules are kept (in __pycache__/, ignored by git), so
# each node and test process does not compile the project and its generated messages
# again (~0.05 s CPU for the arm node's imports). A cache prefix would also recompile
# the standard library, the venv and ROS once into it.
unset PYTHONDONTWRITEBYTECODE PYTHONPYCACHEPREFIX
# the project tooling (tools/: evaluation, benchmarks, demo, soak) is not installed
export PYTHONPATH="$_lt_root${PYTHONPATH:+:$PYTHONPATH}"
set -- "${_lt_args[@]}"
unset _lt_args
if [ "${BASH_SOURCE[0]}" = "$0" ]; then
  [ $# -gt 0 ] || { echo "usage: ./env.sh CMD [ARGS...]" >&2; exit 2; }
  exec "$@"
fi
