#!/usr/bin/env bash
# tests/batch/test_batch.sh -- `panelize batch` without a scheduler (docs/batch.md): every garment
# of a folder gets its folder and its summary row, a broken one is recorded and the others go on
# (exit 1), all good is exit 0; the shards partition the garments exactly (every N-th of the
# name order) and --merge joins them; --resume after a batch killed mid-way runs only the
# unfinished garments; a worker killed from outside (as the OOM killer does) is recorded as
# crashed, one over --timeout as timeout, and the others go on; a manifest's options and poses
# reach their garment; bad batch input is one line and exit 64/66.
#
# SPDX-License-Identifier: GPL-3.0-or-later
set -u

HERE=$(cd "$(dirname "$0")" && pwd)
source "$HERE/../cli/lib.sh"
source "$HERE/lib_garments.sh"

FAST=(--outputs json,svg --quiet)
check "generate the garments" make_garments in 10 broken

# rows FILE: the names in a summary.jsonl, in order
rows() { python3 -c 'import json,sys; print(" ".join(json.loads(l)["name"] for l in open(sys.argv[1])))' "$1"; }
count_status() { python3 -c 'import json,sys; print(sum(json.loads(l)["status"] == sys.argv[2] for l in open(sys.argv[1])))' "$1" "$2"; }

# ------------------------------------------------------------------ a folder, one garment broken
run batch in -o res -j 2 "${FAST[@]}"
check "batch with a broken garment: exit $rc, expected 1" [ "$rc" -eq 1 ]
check "the failure is one stderr line naming the summary: $(cat err)" grep -q 'batch: 1 of 11 garments failed (see res/summary.csv)' err
check "summary.csv: a header and 11 rows" [ "$(wc -l <res/summary.csv)" -eq 12 ]
check "summary.csv header" grep -qx 'name,input,status,exit,category,pieces,darts,goals_met,worst_strain,seconds,peak_rss_mb,resumed,shard,error' res/summary.csv
check "summary.jsonl in name order" [ "$(rows res/summary.jsonl)" = "broken g00 g01 g02 g03 g04 g05 g06 g07 g08 g09" ]
check "broken: failed" [ "$(summary_field res/summary.jsonl broken status)" = failed ]
check "broken: category data, exit 65" [ "$(summary_field res/summary.jsonl broken category)/$(summary_field res/summary.jsonl broken exit)" = data/65 ]
check "broken: the error names its file" grep -q 'broken,in/broken.obj,failed,65,data,.*in/broken.obj: no faces' res/summary.csv
check "broken: no folder" [ ! -e res/broken ]
for g in g00 g03 g06 g09; do
    check "$g: ok" [ "$(summary_field res/summary.jsonl $g status)" = ok ]
    check "$g: its folder has report.json, pattern.svg and the marker" \
        [ -f res/$g/report.json -a -f res/$g/pattern.svg -a -f res/$g/batch.json -a -f res/$g/.panelize ]
    check "$g: pieces and darts as report.json says" python3 - res/$g <<'PY'
import json, sys
folder = sys.argv[1]
report, row = json.load(open(folder + "/report.json")), json.load(open(folder + "/batch.json"))
assert row["pieces"] == report["summary"]["panel_count"] >= 1, (row, report["summary"])
assert row["goals_met"] is report["summary"]["goals_met"], row
assert 0 <= row["worst_strain"] <= 0.05 + 1e-9 and row["seconds"] > 0 and row["peak_rss_mb"] > 1, row
assert row["darts"] == len(report["darts"]), row
PY
done
check "no temporaries" no_temporaries

run batch in/g00.obj in/g01.obj -o out_good "${FAST[@]}"
expect_ok "batch of good garments"
check "all good: the totals on stdout" grep -q '^failed: *0$' out

# ------------------------------------------------------------------ --panels uv: each garment's own panels
# A dataset flattened with its true panels: each garment's UV islands (here: the pieces a first batch
# wrote into garment.obj) are its panels, as `run --panels uv` takes them.
run batch in/g00.obj in/g01.obj -o out_uvsrc --outputs obj,json --quiet
expect_ok "batch writing garment.obj"
mkdir -p uvin && cp out_uvsrc/g00/garment.obj uvin/a.obj && cp out_uvsrc/g01/garment.obj uvin/b.obj
run batch uvin -o out_uv --panels uv --outputs json --quiet
expect_ok "batch --panels uv"
check "batch --panels uv: a garment not flattened with its own panels" python3 -c '
import json, sys
for new, old in (("a", "g00"), ("b", "g01")):
    d, e = (json.load(open("%s/%s/report.json" % pair)) for pair in (("out_uv", new), ("out_uvsrc", old)))
    if d["segmentation"]["panels"] != "given" or d["summary"]["panel_count"] != e["summary"]["panel_count"]:
        sys.exit(1)'
expect_error 64 "only 'uv'" --absent out_bad -- batch in -o out_bad --panels faces.txt

# ------------------------------------------------------------------ shards and merge
for i in 0 1 2; do
    run batch in -o out_shards --shard $i/3 "${FAST[@]}"
    check "shard $i/3: exit $rc" [ "$rc" -le 1 ]
done
check "shard 0/3 takes garments 0, 3, 6, 9 of the name order" [ "$(rows out_shards/summary-0-of-3.jsonl)" = "broken g02 g05 g08" ]
check "shard 1/3" [ "$(rows out_shards/summary-1-of-3.jsonl)" = "g00 g03 g06 g09" ]
check "shard 2/3" [ "$(rows out_shards/summary-2-of-3.jsonl)" = "g01 g04 g07" ]
check "the shards' folders are every good garment's" [ "$(cd out_shards && ls -d g* | tr '\n' ' ')" = "g00 g01 g02 g03 g04 g05 g06 g07 g08 g09 " ]
run batch --merge out_shards --quiet
check "merge: exit 1 (the broken garment)" [ "$rc" -eq 1 ]
check "merged summary.jsonl: every garment once, in order" [ "$(rows out_shards/summary.jsonl)" = "$(rows res/summary.jsonl)" ]
check "merged: the same statuses and pieces as one batch" python3 - res/summary.jsonl out_shards/summary.jsonl <<'PY'
import json, sys
keys = ("name", "status", "exit", "category", "pieces", "darts", "goals_met")
one, merged = ([{k: json.loads(l)[k] for k in keys} for l in open(p)] for p in sys.argv[1:])
assert one == merged, (one, merged)
PY
check "merged summary.csv has 11 rows" [ "$(wc -l <out_shards/summary.csv)" -eq 12 ]
rm out_shards/summary-1-of-3.jsonl
expect_error 66 "summary-1-of-3.jsonl" -- batch --merge out_shards
cp out_shards/summary-0-of-3.jsonl out_shards/summary-0-of-2.jsonl
expect_error 65 "summaries of" -- batch --merge out_shards

# ------------------------------------------------------------------ resume after a killed batch
make_garments slow 8 >/dev/null
"$BIN" batch slow -o out_resume -j 1 "${FAST[@]}" >/dev/null 2>&1 &
batch_pid=$!
for ((t = 0; t < 300; ++t)); do # until two garments are complete (at most 30 s)
    [ "$(ls out_resume/*/batch.json 2>/dev/null | wc -l)" -ge 2 ] && break
    sleep 0.1
done
kill -KILL $batch_pid
wait $batch_pid 2>/dev/null
sleep 1 # a worker that outlived its batch would write its marker now
done_before=$(cd out_resume && ls -d */batch.json 2>/dev/null | cut -d/ -f1 | tr '\n' ' ')
check "killed mid-way: some garments complete, not all: '$done_before'" \
    [ -n "$done_before" -a "$(echo $done_before | wc -w)" -lt 8 ]
check "killed: no summary yet" [ ! -e out_resume/summary.csv ]
mkdir -p saved && for g in $done_before; do cp out_resume/$g/batch.json saved/$g.json; done
run batch slow -o out_resume --resume "${FAST[@]}"
expect_ok "resume"
check "resume: every garment ok" [ "$(count_status out_resume/summary.jsonl ok)" -eq 8 ]
resumed=$(python3 -c 'import json,sys; print(" ".join(r["name"] for r in map(json.loads, open(sys.argv[1])) if r["resumed"]))' out_resume/summary.jsonl)
check "resume skipped exactly the complete garments: '$resumed' vs '$done_before'" [ "$resumed " = "$done_before" ]
for g in $done_before; do
    check "$g: its folder was not redone" cmp -s saved/$g.json out_resume/$g/batch.json
done
check "resume: the stdout totals say so" grep -q "^ok: *8 ($(echo $done_before | wc -w) resumed)" out
check "no temporaries after the kill and resume" [ -z "$(find out_resume -name '.*.tmp-*' -o -name '*.tmp-*' | head -1)" ]

# ------------------------------------------------------------------ a crashed worker, a time-out
mkdir -p hard
"$BIN" generate bodice -o hard/a_big.obj --faces 60000 --quiet
cp in/g00.obj in/g01.obj hard/
"$BIN" batch hard -o out_crash -j 1 "${FAST[@]}" >/dev/null 2>&1 &
batch_pid=$!
worker=""
for ((t = 0; t < 100; ++t)); do
    sleep 0.1
    worker=$(pgrep -P $batch_pid | head -1)
    [ -n "$worker" ] && break
done
sleep 0.5
[ -n "$worker" ] && kill -KILL "$worker"
wait $batch_pid
rc=$?
check "a crashed worker: the batch goes on and exits 1 (exit $rc)" [ "$rc" -eq 1 ]
check "a_big: crashed, exit 137 (signal 9)" [ "$(summary_field out_crash/summary.jsonl a_big status)/$(summary_field out_crash/summary.jsonl a_big exit)" = crashed/137 ]
check "a_big: category crash, the signal named" grep -q 'a_big,hard/a_big.obj,crashed,137,crash,.*signal 9' out_crash/summary.csv
check "after the crash the others are ok" [ "$(count_status out_crash/summary.jsonl ok)" -eq 2 ]

start=$(date +%s)
run batch hard -o out_timeout --timeout 1 -j 2 "${FAST[@]}"
elapsed=$(($(date +%s) - start))
check "a time-out: exit 1 ($rc)" [ "$rc" -eq 1 ]
check "a_big: timeout, exit 124, category timeout" [ "$(summary_field out_timeout/summary.jsonl a_big status)/$(summary_field out_timeout/summary.jsonl a_big exit)/$(summary_field out_timeout/summary.jsonl a_big category)" = timeout/124/timeout ]
check "a_big: killed after about 1 s ($(summary_field out_timeout/summary.jsonl a_big seconds))" \
    python3 -c "import sys; assert 1 <= float(sys.argv[1]) < 3" "$(summary_field out_timeout/summary.jsonl a_big seconds)"
check "the time-out did not wait for the garment ($elapsed s)" [ "$elapsed" -lt 15 ]
check "after the time-out the others are ok" [ "$(count_status out_timeout/summary.jsonl ok)" -eq 2 ]
check "a_big: no folder, no half-written one" [ ! -e out_timeout/a_big -a -z "$(ls -A out_timeout | grep tmp)" ]

# ------------------------------------------------------------------ a manifest
"$BIN" generate sleeve -o in/posed.obj --faces 600 --poses 1 --quiet
mkdir -p lists
cat >lists/garments.txt <<EOF
# garment  options (paths relative to this file)
../in/g00.obj --iterations 7 --name custom
../in/posed.obj --pose ../in/posed.pose1.obj
"../in/g01.obj"   # a comment
EOF
run batch lists/garments.txt -o out_manifest "${FAST[@]}"
expect_ok "a manifest"
check "manifest: the garments' folders" [ -d out_manifest/custom -a -d out_manifest/in-posed -a -d out_manifest/in-g01 ]
check "manifest: --iterations reached its garment" python3 -c 'import json; assert json.load(open("out_manifest/custom/report.json"))["parameters"]["iterations"] == 7'
check "manifest: the others keep the default" python3 -c 'import json; assert json.load(open("out_manifest/in-g01/report.json"))["parameters"]["iterations"] == 20'
check "manifest: the pose reached its garment" python3 -c 'import json; assert json.load(open("out_manifest/in-posed/report.json"))["input"]["poses"] == 1'
run batch lists/garments.txt -o out_manifest --json --quiet --outputs json
check "--json: the totals as JSON" python3 -c 'import json; d = json.load(open("out")); assert d["garments"] == 3 and d["ok"] == 3 and d["failed"] == 0, d'

# ------------------------------------------------------------------ bad batch input: one line, 64 or 66
printf '../in/g00.obj --max-strain lots\n' >lists/bad_value.txt
printf '../in/g00.obj\n../in/g01.obj --no-such-option\n' >lists/bad_option.txt
printf '../in/g00.obj\n"../in/g01.obj\n' >lists/bad_quote.txt
printf '../in/notes.doc\n' >lists/bad_file.txt
expect_error 66 "no_such_folder" -- batch no_such_folder -o out_bad
expect_error 64 "bad_value.txt:1" --absent out_bad -- batch lists/bad_value.txt -o out_bad
expect_error 64 "bad_option.txt:2" --absent out_bad -- batch lists/bad_option.txt -o out_bad
expect_error 64 "bad_quote.txt:2" --absent out_bad -- batch lists/bad_quote.txt -o out_bad
expect_error 64 "bad_file.txt:1" --absent out_bad -- batch lists/bad_file.txt -o out_bad
expect_error 64 "--shard" --absent out_bad -- batch in -o out_bad --shard 3/3
expect_error 64 "--shard" --absent out_bad -- batch in -o out_bad --shard 1
expect_error 64 "--shard" --absent out_bad -- batch in -o out_bad --shard -1/2
expect_error 64 "--jobs" --absent out_bad -- batch in -o out_bad --jobs 0
expect_error 64 "--timeout" --absent out_bad -- batch in -o out_bad --timeout -5
expect_error 64 "-o OUTROOT" -- batch in
expect_error 64 "--pose" -- batch in -o out_bad --pose in/g00.obj
expect_error 64 "would both write the folder g00" --absent out_bad -- batch in in/g00.obj -o out_bad
mkdir -p empty
expect_error 64 "empty" --absent out_bad -- batch empty -o out_bad
touch notes.doc
expect_error 64 "notes.doc" --absent out_bad -- batch notes.doc -o out_bad

finish
