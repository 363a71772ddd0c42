#!/usr/bin/env bash
# Byte-for-byte comparison of murk's outputs against another commit, for refactors that must not
# change behaviour: builds BASE in a worktree, runs one fixed command set with both binaries, and
# lists every output that differs.
#
#   scripts/same-outputs.sh BASE [OUTDIR]
#
# The command set: every scene (that BASE has too) rendered at 4 spp with a fixed seed on a 16² grid; every method on
# the demo capture; the paper's Z configuration (128² × 4096) with fast PF; the shared real captures
# (../shared/data/real/cdt_lindell2020, when present) imported and reconstructed with CDT and PF; and
# `murk figure real`. Exit status 0 when all outputs are identical.
set -euo pipefail
base=${1:?usage: scripts/same-outputs.sh BASE [OUTDIR]}
root=$(cd "$(dirname "$0")/.." && pwd)
out=${2:-$(mktemp -d /tmp/murk-same-XXXXXX)}
real="$root/../shared/data/real/cdt_lindell2020"

wt="$out/base-src"
if [ ! -d "$wt" ]; then
    git -C "$root" worktree add -q --detach "$wt" "$base"
fi
echo "building $base in $wt"
(cd "$wt" && CARGO_TARGET_DIR="$out/base-target" cargo build --release -q)
echo "building the working tree"
(cd "$root" && cargo build --release -q)

run_set() {
    local murk=$1 dir=$2
    rm -rf "$dir" && mkdir -p "$dir"
    for scene in "$root"/scenes/*.toml; do
        local name
        name=$(basename "$scene" .toml)
        # A scene added since BASE may use what BASE cannot read.
        [ -e "$wt/scenes/$name.toml" ] || continue
        "$murk" render "$scene" --spp 4 --seed 1 --grid 16 --out "$dir/render-$name.h5" -q
    done
    "$murk" demo --out "$dir/demo" -q
    local cap="$dir/demo/capture.h5"
    for m in pf pf-exact bp fbp; do
        "$murk" reconstruct "$cap" --method "$m" --out "$dir/demo-$m.npy" -q
    done
    "$murk" synth --out "$dir/confocal.h5" --kind confocal --grid 32 --bins 512 --bin-width 0.005 \
        --target t:0.5 -q
    for m in pf lct fk cdt; do
        "$murk" reconstruct "$dir/confocal.h5" --method "$m" --out "$dir/confocal-$m.npy" -q
    done
    "$murk" synth --out "$dir/z.h5" --kind laser-grid --wall-size 2 --grid 128 --bins 4096 \
        --bin-width 0.0009 --start 3.5 --target z:2.0 --cosines -q
    "$murk" reconstruct "$dir/z.h5" --out "$dir/z-pf.npy" --volume=-0.99:0.99:73,-0.99:0.99:59,1.5:2.5:73 -q
    if [ -d "$real" ]; then
        for s in letter_s mannequin letter_t cones letters_ut; do
            "$murk" import "$real/$s.mat" --format cdt --out "$dir/real-$s.h5" -q
            "$murk" reconstruct "$dir/real-$s.h5" --method cdt --out "$dir/real-$s-cdt.npy" -q
            "$murk" reconstruct "$dir/real-$s.h5" --method pf --t-offset slab --out "$dir/real-$s-pf.npy" -q
        done
        "$murk" figure real --data "$real" --out "$dir/figure" --runs 1 -q
    fi
}

echo "running the command set with $base"
run_set "$out/base-target/release/murk" "$out/base"
echo "running the command set with the working tree"
run_set "$root/target/release/murk" "$out/new"

status=0
while IFS= read -r f; do
    rel=${f#"$out/base/"}
    case "$rel" in
        # Timings and the summary tables that quote them differ run to run.
        figure/index.html | demo/index.html) continue ;;
    esac
    if ! cmp -s "$f" "$out/new/$rel"; then
        echo "differs: $rel"
        status=1
    fi
done < <(find "$out/base" -type f | sort)
[ $status = 0 ] && echo "all outputs identical ($out)"
git -C "$root" worktree remove --force "$wt"
exit $status
