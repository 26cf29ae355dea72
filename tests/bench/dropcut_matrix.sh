#!/usr/bin/env bash
# dropcut_matrix: every drop-cutter strategy with every cutter on every test surface, as a user
# runs it (`curvestep toolpath --cutter C --strategy S --scallop H --tol T --check --stats`), and
# the independent check's verdict (issue 20: gouge within tol, scallop at most H, everywhere).
# Surfaces: the Utah teapot at scale 10 (R 2, bull-nose (2, 0.5), H 0.05, tol 0.01), the teacup
# and the halved five-sided patch of tests/cli/lib/shapes.sh (R 1.5, bull-nose (1.5, 0.5), H 0.1,
# tol 0.02). Usage: dropcut_matrix.sh [OUT.csv]; Markdown on stdout, progress on stderr.
# DCM_SURFACES (default "teapot cup pent") picks surfaces; CS_BUILD the build directory.
set -u
cd "$(dirname "$0")/../.."
. scripts/args.sh
cs_args "usage: tests/bench/dropcut_matrix.sh [OUT.csv]\nRuns curvestep toolpath --check for every drop-cutter strategy x cutter x test surface\n(DCM_SURFACES, default \"teapot cup pent\"); Markdown on stdout, CSV in OUT.csv." 1 "$@"
. tests/cli/lib/shapes.sh
B=${CS_BUILD:-build}
CS=$B/curvestep
csv=${1:-build/bench/dropcut_matrix.csv}
[ -x "$CS" ] || { echo "dropcut_matrix: $CS not built" >&2; exit 2; }
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
mkdir -p "$(dirname "$csv")"
cs_shape_cup "$T/cup.txt"
cs_shape_pent "$T/pent.txt"

echo "## Drop-cutter finishing: every strategy, every cutter, every test surface (dropcut_matrix)"
echo
echo "\`curvestep toolpath --cutter C --strategy S --scallop H --tol T --check --stats\` (issue 20):"
echo "the teapot at scale 10 with R 2 (bull-nose corner 0.5), H 0.05, tol 0.01; the teacup and the"
echo "halved five-sided patch (tests/cli/lib/shapes.sh) with R 1.5 (corner 0.5), H 0.1, tol 0.02."
echo "Gouge and scallop by the independent check (docs/surfaces.md, item 6); pass = exit 0"
echo "(gouge <= tol and scallop <= H). CPU = user + system seconds of the whole command, check"
echo "included; load = the 1-minute load average before the run (the machine has $(nproc) cores)."
echo
echo "| surface | strategy | cutter | passes | points | gouge mm | scallop mm | at | unreachable mm² | CPU s | load | verdict |"
echo "|---|---|---|---:|---:|---:|---:|---|---:|---:|---:|---|"
echo "surface,strategy,cutter,passes,points,gouge_mm,scallop_mm,unreachable_mm2,cpu_s,load,rc" >"$csv"
fails=0
for s in ${DCM_SURFACES:-teapot cup pent}; do
    case $s in
    teapot) src=(--patches tests/data/teapot/newell_teapot.txt --scale 10); R=2; H=0.05; tol=0.01 ;;
    cup | pent) src=(--patches "$T/$s.txt"); R=1.5; H=0.1; tol=0.02 ;;
    *) echo "dropcut_matrix: unknown surface $s" >&2; exit 2 ;;
    esac
    for st in raster waterline raster+waterline; do
        for c in "ball:$R" "flat:$R" "bull:$R:0.5"; do
            echo "dropcut_matrix: $s $st $c" >&2
            load=$(cut -d' ' -f1 /proc/loadavg)
            /usr/bin/time -f "%U %S" -o "$T/time" "$CS" toolpath "${src[@]}" --cutter "$c" \
                --strategy "$st" --scallop "$H" --tol "$tol" --check --stats >/dev/null 2>"$T/err"
            rc=$?
            cpu=$(tail -n1 "$T/time" | awk '{ printf "%.1f", $1 + $2 }' 2>/dev/null)
            read -r passes points < <(sed -n 's/.*, \([0-9]*\) passes (.*, \([0-9]*\) points,.*/\1 \2/p' "$T/err" | head -n1)
            read -r gouge scallop at < <(sed -n 's/.*gouge \([0-9.]*\) mm, scallop \([0-9.]*\) mm at (\([^)]*\)).*/\1 \2 \3/p' "$T/err" | tr -d ',' | head -n1)
            unr=$(sed -n 's/.*unreachable: [0-9]* nodes (\([0-9.]*\) mm^2).*/\1/p' "$T/err" | head -n1)
            # The verdict from the figures themselves, not only the command's exit status.
            v=$(awk -v rc="$rc" -v g="${gouge:-}" -v s="${scallop:-}" -v tol="$tol" -v h="$H" 'BEGIN {
                if (g == "" || s == "") { print "**FAIL (no check line)**"; exit }
                r = ""; if (g + 0 > tol + 0) r = r " gouge > tol"; if (s + 0 > h + 0) r = r " scallop > H"
                if (rc != 0) r = r " exit " rc
                print (r == "" ? "pass" : "**FAIL:" r "**") }')
            case $v in pass) ;; *) fails=$((fails + 1)) ;; esac
            [ -n "${gouge:-}" ] || v="$v $(tail -n1 "$T/err" | cut -c1-120)"
            echo "| $s | $st | ${c%%:*} | ${passes:--} | ${points:--} | ${gouge:--} | ${scallop:--} | ${at:+(}${at:--}${at:+)} | ${unr:-0} | ${cpu:--} | $load | $v |" | sed 's/(\([^ ]*\) \([^ )]*\))/(\1, \2)/'
            echo "$s,$st,${c%%:*},${passes:-},${points:-},${gouge:-},${scallop:-},${unr:-0},${cpu:-},$load,$rc" >>"$csv"
            passes='' points='' gouge='' scallop='' at=''
        done
    done
done
echo
echo "Runs failing the check: $fails."
