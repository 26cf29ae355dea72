# Helpers of the tests that drive `curvestep serve` (sourced after common.sh, never run: it lives
# in lib/ because scripts/run-tests.sh runs every tests/cli/*.sh as a test). With S the daemon's
# socket and N the job's segment count:
#   dmn_job LINE        writes a one-move G-code job (G21 G90, then LINE) to JOB=$T/line.nc and
#                       sets N to its segment count as `curvestep plan` counts them (one
#                       assertion: the plan has more than 100);
#   C ARGS...           a client command on $S, bounded by `timeout`;
#   dmn_start ARGS...   `curvestep serve ARGS --socket $S` in the background (DPID; serve's
#                       stderr in $T/serve.err), waits for the socket;
#   dmn_progress        job 1's executed count from `status` ("" when it is not running);
#   dmn_quarter         succeeds once job 1 has executed a quarter of N (for wait_until);
#   dmn_still           succeeds once the link confirmed job 1's hold: status shows "(held)"
#                       (the device reported HELD, or the GPIO step thread is at rest; before
#                       that it shows "(holding)"), for wait_until;
#   dmn_finished        succeeds once job 1 is done, failed or cancelled.
C() { timeout -k 5 30 "$CS" "$@" --socket "$S"; }
dmn_start() {
    timeout -k 5 400 "$CS" serve "$@" --socket "$S" 2>"$T/serve.err" &
    DPID=$!
    pids+=($DPID)
    wait_until 30 [ -S "$S" ]
}
dmn_progress() { C status 2>/dev/null | sed -n "s/^job 1 running: .*: \([0-9]*\)\/$N segments.*/\1/p"; }
dmn_quarter() {
    local p
    p=$(dmn_progress)
    [ "${p:-0}" -ge $((N / 4)) ]
}
dmn_still() { C status 2>/dev/null | grep -qE "^job 1 running: .*: [0-9]+/$N segments executed \(held\)$"; }
dmn_finished() { C status 2>/dev/null | grep -qE "^job 1 (done|failed|cancelled)"; }
dmn_job() {
    JOB=$T/line.nc
    printf 'G21 G90\n%s\n' "$1" >"$JOB"
    N=$("$CS" plan -o /dev/null "$JOB" 2>&1 | sed -n 's/.* blocks, \([0-9]*\) segments,.*/\1/p')
    expect "plan: the job has segments" [ "${N:-0}" -gt 100 ]
}
