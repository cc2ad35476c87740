# Process supervision for the bash scripts that start ROS nodes with rosrun (no roslaunch):
# src/ehc_bringup/scripts/demo.sh and src/ehc_realman/scripts/run_realman.sh. Source it:
#   source "<path>/supervise.sh"
#   SUP_TAG=demo.sh SUP_LOG_DIR=/some/logs     # message prefix, one <name>.log per process
#   sup_private_master PORT ROS_HOME; sup_start_master || exit 2   (or use an existing master)
#   sup_install_traps "interrupted, stopping" 130
#   sup_start NAME COMMAND...                    # background, output to $SUP_LOG_DIR/NAME.log
#   sup_watch --until NAME --limit SECONDS       # returns when a process ends or time is up
#   sup_stop_all
# Every process started (or adopted) here is stopped by its process id: SIGINT to each started
# one (SIGTERM to an adopted one: a pipeline the caller started in the background ignores
# SIGINT), newest first, then SIGKILL to those still alive after SUP_GRACE_TENTHS tenths of a second; a private
# master (sup_start_master) is stopped last, with SIGTERM once the others are gone (after a
# Ctrl-C rosmaster could take until the SIGKILL to exit on SIGINT: every stop took 5 s).
# Functions set variables of the calling shell: call them directly, never inside $(...).

SUP_TAG="${SUP_TAG:-$(basename "$0")}"  # prefix of the messages printed here
SUP_LOG_DIR="${SUP_LOG_DIR:-.}"         # sup_start writes $SUP_LOG_DIR/<name>.log
SUP_GRACE_TENTHS="${SUP_GRACE_TENTHS:-50}"  # 5 s for a clean shutdown after SIGINT
SUP_PIDS=()                             # the supervised processes, in start order
SUP_NAMES=()                            # their names (log file names without .log)
SUP_STOP_SIGNALS=()                     # the signal that stops each: INT (started) or TERM (adopted)
SUP_LAST_PID=                           # the process sup_start started last
SUP_DEAD=                               # sup_watch: the process that exited ...
SUP_DEAD_RC=                            # ... and its exit code
SUP_MASTER_PID=                         # the private master (sup_start_master), stopped last
_sup_stopped=0

# sup_start NAME COMMAND...: runs COMMAND in the background with line-buffered output (progress
# is streamed) into $SUP_LOG_DIR/NAME.log; SUP_LAST_PID is its process id (stdbuf and rosrun
# exec the node: the id is the node's).
sup_start() {
  local name="$1"
  shift
  stdbuf -oL -eL "$@" >"$SUP_LOG_DIR/$name.log" 2>&1 &
  SUP_LAST_PID=$!
  SUP_PIDS+=("$SUP_LAST_PID")
  SUP_NAMES+=("$name")
  SUP_STOP_SIGNALS+=(INT)
}

# sup_adopt NAME PID: supervise a background process the caller started itself.
sup_adopt() {
  SUP_NAMES+=("$1")
  SUP_PIDS+=("$2")
  SUP_STOP_SIGNALS+=(TERM)
}

# sup_pid NAME: prints the process id of NAME.
sup_pid() {
  local i
  for i in "${!SUP_NAMES[@]}"; do
    [ "${SUP_NAMES[$i]}" = "$1" ] && { echo "${SUP_PIDS[$i]}"; return 0; }
  done
  return 1
}

# sup_log_tail NAME: the last lines of NAME's log, on stderr.
sup_log_tail() {
  tail -n 5 "$SUP_LOG_DIR/$1.log" >&2
}

# sup_stop_all: stops every supervised process (once; later calls return at once) and removes
# the traps: SIGINT (adopted: SIGTERM) newest first (the master excepted), the master SIGTERM
# once they are gone,
# SIGKILL to anything alive after the grace period, then reaps them.
sup_stop_all() {
  [ "$_sup_stopped" = 1 ] && return 0
  _sup_stopped=1
  trap - INT TERM EXIT
  local i p others=()
  for ((i = ${#SUP_PIDS[@]} - 1; i >= 0; i--)); do
    [ "${SUP_PIDS[$i]}" = "$SUP_MASTER_PID" ] && continue
    others+=("${SUP_PIDS[$i]}")
    kill "-${SUP_STOP_SIGNALS[$i]}" "${SUP_PIDS[$i]}" 2>/dev/null
  done
  _sup_wait_gone "${others[@]}"
  if [ -n "$SUP_MASTER_PID" ]; then
    kill -TERM "$SUP_MASTER_PID" 2>/dev/null
    _sup_wait_gone "$SUP_MASTER_PID"
  fi
  for p in "${SUP_PIDS[@]}"; do kill -KILL "$p" 2>/dev/null; done
  [ ${#SUP_PIDS[@]} -gt 0 ] && wait "${SUP_PIDS[@]}" 2>/dev/null
  return 0
}

# _sup_wait_gone PID...: returns once none of them is running (a zombie counts as gone), at most
# SUP_GRACE_TENTHS tenths of a second.
_sup_wait_gone() {
  local i p line alive
  for ((i = 0; i < SUP_GRACE_TENTHS; i++)); do
    alive=0
    for p in "$@"; do
      # The state after the command name in /proc/PID/stat ("Z": exited, not yet reaped).
      read -r line 2>/dev/null </proc/"$p"/stat || continue
      line="${line##*) }"
      [ "${line%% *}" != Z ] && alive=1
    done
    [ "$alive" = 0 ] && return 0
    sleep 0.1
  done
}

# sup_install_traps MESSAGE CODE: on SIGINT / SIGTERM print an empty line and
# "$SUP_TAG: MESSAGE", stop everything and exit CODE; on any exit stop everything.
sup_install_traps() {
  # shellcheck disable=SC2064  # expanded now, on purpose
  trap "echo; echo $(printf '%q' "$SUP_TAG: $1"); sup_stop_all; exit $2" INT TERM
  trap 'sup_stop_all' EXIT
}

# sup_watch [--until NAME] [--ignore NAME]... [--limit SECONDS]: polls every 0.2 s. Returns
#   0 when NAME (--until) has exited (the run's normal end),
#   1 when any other process that is not ignored has exited: SUP_DEAD is its name, SUP_DEAD_RC
#     its exit code (the first one in start order),
#   2 when SECONDS of wall clock have passed,
#   3 on a wrong argument.
# Without --until and --limit it returns only when a process exits.
sup_watch() {
  local last= limit= ignore=" " deadline= i
  while [ $# -gt 0 ]; do
    case "$1" in
      --until) last="$2"; shift 2 ;;
      --ignore) ignore+="$2 "; shift 2 ;;
      --limit) limit="$2"; shift 2 ;;
      *) echo "$SUP_TAG: sup_watch: unknown argument '$1'" >&2; return 3 ;;
    esac
  done
  [ -n "$limit" ] && deadline=$(( $(date +%s) + limit ))
  while :; do
    if [ -n "$last" ] && ! kill -0 "$(sup_pid "$last")" 2>/dev/null; then
      return 0
    fi
    for i in "${!SUP_PIDS[@]}"; do
      [ "${SUP_NAMES[$i]}" = "$last" ] && continue
      [[ "$ignore" == *" ${SUP_NAMES[$i]} "* ]] && continue
      if ! kill -0 "${SUP_PIDS[$i]}" 2>/dev/null; then
        SUP_DEAD="${SUP_NAMES[$i]}"
        wait "${SUP_PIDS[$i]}"
        SUP_DEAD_RC=$?
        return 1
      fi
    done
    if [ -n "$deadline" ] && [ "$(date +%s)" -ge "$deadline" ]; then
      return 2
    fi
    sleep 0.2
  done
}

# sup_clear_params NAMESPACE...: deletes each node's private parameters (/<node name>) left by
# an earlier run on the same master, so that a node gets exactly this run's overrides.
sup_clear_params() {
  local ns
  for ns in "$@"; do
    if rosparam list "$ns" 2>/dev/null | grep -q .; then
      rosparam delete "$ns" >/dev/null ||
        { echo "$SUP_TAG: cannot delete the parameters $ns" >&2; return 1; }
    fi
  done
}

# sup_free_port FIRST: prints the first free TCP port on 127.0.0.1 from FIRST up (200 tried).
sup_free_port() {
  /usr/bin/python3 - "$1" <<'EOF'
import socket, sys
for p in range(int(sys.argv[1]), int(sys.argv[1]) + 200):
    s = socket.socket()
    try:
        s.bind(("127.0.0.1", p)); s.close(); print(p); break
    except OSError:
        s.close()
EOF
}

# sup_private_master PORT ROS_HOME: the environment of a private master on 127.0.0.1:PORT with
# its own ROS_HOME (logs in ROS_HOME/log): never touches another ROS system on this machine.
sup_private_master() {
  export ROS_MASTER_URI="http://127.0.0.1:$1"
  export ROS_HOSTNAME=127.0.0.1
  unset ROS_IP
  export ROS_HOME="$2"
  export ROS_LOG_DIR="$ROS_HOME/log"
  mkdir -p "$ROS_LOG_DIR"
}

# sup_master_pid: the process id the master at ROS_MASTER_URI reports (empty if none answers).
sup_master_pid() {
  /usr/bin/python3 -c "import sys, xmlrpc.client as x
print(x.ServerProxy(sys.argv[1]).getPid(sys.argv[2])[2])" "$ROS_MASTER_URI" "/$SUP_TAG" 2>/dev/null
}

# sup_start_master: starts rosmaster (process "rosmaster", log rosmaster.log) on the port of
# ROS_MASTER_URI and waits until it answers (100 tries, 0.1 s apart). Returns 0 when it answers,
# 1 if another master answers there (two runs started at the same instant can pick the same free
# port), 2 if ours exited or never answered (its log says why).
sup_start_master() {
  local port="${ROS_MASTER_URI##*:}" master pid try
  port="${port%%/*}"
  sup_start rosmaster rosmaster --core -p "$port"
  master=$SUP_LAST_PID
  SUP_MASTER_PID=$master
  for ((try = 0; try < 100; try++)); do
    pid=$(sup_master_pid)
    [ "$pid" = "$master" ] && return 0
    [ -n "$pid" ] && return 1                      # another master
    kill -0 "$master" 2>/dev/null || return 2      # ours died
    # No XML-RPC answer yet (or a stand-in master that only serves parameters): the parameter
    # server answering is enough.
    rosparam list / >/dev/null 2>&1 && return 0
    sleep 0.1
  done
  return 2
}
