#!/usr/bin/env bash
# The layers are enforced by the build (issue 14 item 6, docs/architecture.md): each layer is
# compiled with the include paths of the layers below it only, so including a header from a
# layer above fails to compile; and the host program is linked without the simulator's library,
# so it holds no simulator, device-application or port symbol. The flags are the Makefile's own
# (make print-VAR); each probe includes one header and is compiled with one layer's flags.
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"

flags() { make -s --no-print-directory CS_DEPS_DONE=1 "print-$1"; }

# probe LAYER_FLAGS_VAR HEADER WANT(ok|fail)
probe() {
    local var=$1 hdr=$2 want=$3 f
    f=$(flags "$var")
    printf '#include "%s"\nint cs_layer_probe;\n' "$hdr" >"$T/probe.c"
    # shellcheck disable=SC2086 # the flags are a list of words
    if cc $f -c "$T/probe.c" -o "$T/probe.o" 2>"$T/cc.err"; then got=ok; else got=fail; fi
    if [ "$got" = "$want" ]; then
        ok
    elif [ "$want" = fail ]; then
        ko "$var reaches up: $hdr compiles with the flags of that layer"
    else
        ko "$var cannot include its own layer's $hdr: $(head -c 300 "$T/cc.err")"
    fi
}

# core: only itself
probe CORE_CFLAGS cs_fixed.h ok
probe CORE_CFLAGS cs_trace.h ok
for h in port.h cs_fw_app.h cs_jobplan.h cs_sim.h port_posix.h fw_test.h; do
    probe CORE_CFLAGS $h fail
done
# the device application: core + port seam
probe APP_CFLAGS cs_fw_app.h ok
probe APP_CFLAGS port.h ok
for h in cs_jobplan.h cs_sim.h port_posix.h; do probe APP_CFLAGS $h fail; done
# the host: core + host, never the simulator, the application or a port
probe HOST_ONLY_CFLAGS cs_jobplan.h ok
probe HOST_ONLY_CFLAGS cs_proto.h ok
for h in cs_sim.h cs_fw_app.h port.h port_posix.h; do probe HOST_ONLY_CFLAGS $h fail; done
# the simulator: everything below it
for h in cs_sim.h cs_fw_app.h cs_jobplan.h port_posix.h; do probe SIM_CFLAGS $h ok; done
probe SIM_CFLAGS fw_test.h fail

# The rules use those flags: the command make would run for one object of each layer.
variant=plain
case "$B" in */asan) variant=asan ;; esac
cmd_for() {
    make -n --no-print-directory CS_DEPS_DONE=1 VARIANT=$variant -W "$1" "$2" 2>/dev/null |
        grep -E " -c $1 "
}
c=$(cmd_for firmware/core/cs_fixed.c "$B/obj/firmware/core/cs_fixed.o")
expect "core object compiled with -Ifirmware/core only" \
    test "$(grep -oE -- '-I[^ ]+' <<<"$c" | tr '\n' ' ')" = "-Ifirmware/core "
c=$(cmd_for host/cs_conv.c "$B/obj/host/cs_conv.o")
expect "host object compiled without sim/ or firmware/app" \
    bash -c '[ -n "$1" ] && ! grep -qE -- "-I(sim|firmware/app|firmware/ports)( |$)" <<<"$1"' _ "$c"
c=$(cmd_for sim/cs_sim.c "$B/obj/sim/cs_sim.o")
expect "sim object compiled with sim/" grep -q -- "-Isim" <<<"$c"

# The host program: no simulator, device-application or port code linked in.
need_bin "$CS"
n=$(nm "$CS" | awk '$2 ~ /^[TtDdBb]$/ {print $3}' | grep -cE '^(cs_sim_|cs_fw_|port_)' || true)
expect "curvestep links no cs_sim_/cs_fw_/port_ symbol (found $n)" test "$n" -eq 0
expect "libcshost.a holds no simulator object" \
    bash -c '! ar t "$1" | grep -qE "^(cs_sim|port_posix|cs_fw_)"' _ "$B/libcshost.a"
expect "libcssim.a holds the simulator, the application and the POSIX port" \
    bash -c 'ar t "$1" | grep -q "^cs_sim.o" && ar t "$1" | grep -q "^cs_fw_app.o" && ar t "$1" | grep -q "^port_posix.o"' _ "$B/libcssim.a"
finish
