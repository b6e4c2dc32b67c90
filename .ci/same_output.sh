#!/bin/bash
# Every bundled scenario's `twin run FILE --json`, in this tree and in the tree of REV, compared
# byte for byte: a change that should not move any number proves it here.
#   usage: .ci/same_output.sh REV   (prints one line per scenario that differs; exit 1 if any)
set -u
rev=${1:?usage: .ci/same_output.sh REV}
work=$(mktemp -d)
git worktree add -q --detach "$work/before" "$rev"
run_all() {  # run_all TREE OUT: each scenario's JSON into OUT/<name>.json
    mkdir -p "$2"
    for f in "$1"/twin/scenarios/*.toml; do
        (cd "$1" && UV_PYTHON_DOWNLOADS=never uv run -q twin run "$f" --json) > "$2/$(basename "$f" .toml).json" 2> /dev/null
    done
}
run_all "$work/before" "$work/out_before"
run_all "$(pwd)" "$work/out_after"
status=0
for f in "$work"/out_before/*.json; do
    cmp -s "$f" "$work/out_after/$(basename "$f")" || { echo "differs: $(basename "$f" .json)"; status=1; }
done
echo "$(ls "$work"/out_before | wc -l) scenarios compared against $rev"
git worktree remove --force "$work/before"
rm -rf "$work"
exit $status
