# Sourced by the scripts that take arguments (never run): the command line they share.
#   cs_args USAGE MAX "$@"
# --help or -h prints USAGE and exits 0; an argument starting with '-' that the script does not
# take, or more than MAX arguments (-1: any number), prints USAGE on stderr and exits 2, before
# the script does anything.
cs_args() {
    local usage=$1 max=$2 a
    shift 2
    for a in "$@"; do
        case "$a" in
        -h | --help) printf '%b\n' "$usage"; exit 0 ;;
        -*) printf '%s: unknown option %s\n%b\n' "${0##*/}" "$a" "$usage" >&2; exit 2 ;;
        esac
    done
    if [ "$max" -ge 0 ] && [ $# -gt "$max" ]; then
        printf '%s: too many arguments\n%b\n' "${0##*/}" "$usage" >&2
        exit 2
    fi
}
