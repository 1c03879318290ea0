#!/usr/bin/env bash
# A sweep with two grid factors (2 values x 2 values x 2 controllers, a drawn impulse) writes
# small multiples and pivot tables (docs/design.md section 8, sweep summaries): crash_rate.png
# has one panel per grid cell (its CSV: four panels, each with both controllers' series under
# the same names), laid out two by two; summary.md has one table per controller with the first
# factor's values as rows and the second's as columns, and the crash rate per bin pooled per
# controller (one column each) instead of one column per group. The same sweep with one grid
# factor keeps the one-panel plot and the table with one column per group.
# Usage: sweep_grid_factors_test.sh HPA_BINARY SCENARIOS_DIR OUT_DIR
set -uo pipefail
hpa=$1; scen=$2; out=$3
rm -rf "$out"; mkdir -p "$out"
# shellcheck source=cli_test_lib.sh
source "$(dirname "$0")/cli_test_lib.sh"

# a fast base: ground truth, the analytic camera, a short hover with a drawn impulse
impulse_hover_base "$out/base.yaml" grid_factors_base 0.6 0.2
cat > "$out/two.yaml" <<'YAML'
base: base.yaml
runs: 3
seed: 5
vary:
  events.0.impulse.2: {uniform: [0.05, 0.3], label: "impulse z [N s]"}
  world.payload_mass: {grid: [0.08, 0.12]}
  events.0.at: {grid: [0.1, 0.3]}
  controller.type: {grid: [geometric, nonhybrid_mpc]}
YAML
grep -v "events.0.at" "$out/two.yaml" > "$out/one.yaml"

"$hpa" sweep "$out/two.yaml" --out "$out/two" --jobs 2 > "$out/two.log" 2>&1 \
  || fail "two-factor sweep failed: $(tail -3 "$out/two.log")"
"$hpa" sweep "$out/one.yaml" --out "$out/one" --jobs 2 > "$out/one.log" 2>&1 \
  || fail "one-factor sweep failed: $(tail -3 "$out/one.log")"
for f in two/crash_rate.png two/crash_rate.csv two/summary.md one/crash_rate.png one/summary.md; do
  [ -s "$out/$f" ] || fail "no $f"
done

python3 - "$out" <<'PY' || fail "layout checks failed"
import csv, re, struct, sys
out = sys.argv[1]
controllers = ["geometric", "nonhybrid_mpc"]

def png_size(path):
    with open(path, "rb") as f:
        head = f.read(24)
    assert head[:8] == b"\x89PNG\r\n\x1a\n", path + " is not a PNG"
    return struct.unpack(">II", head[16:24])

def panels(path):
    """panel title -> the set of series names drawn in it"""
    found = {}
    for row in csv.DictReader(open(path)):
        found.setdefault(row["panel"], set()).add(row["series"])
    return found

# two factors: one panel per grid cell, titled by its values, every panel the same series names
two = panels(out + "/two/crash_rate.csv")
want = {"payload_mass=%s, at=%s" % (m, a) for m in ("0.08", "0.12") for a in ("0.1", "0.3")}
assert set(two) == want, "panels %s, expected %s" % (sorted(two), sorted(want))
for title, names in two.items():
    for c in controllers:
        assert c in names, "panel %s lacks %s's crash rate: %s" % (title, c, names)
    assert names == two[sorted(two)[0]], "panels name their series differently: %s" % two
# two columns of panels at least 400 px wide, two rows of 260 px under the header
width, height = png_size(out + "/two/crash_rate.png")
assert width >= 800 and width < 1200 and height >= 2 * 260 + 50, (width, height)

# one factor: today's single panel, 1000 x 600
one = panels(out + "/one/crash_rate.csv")
assert len(one) == 1, "one factor drew %d panels" % len(one)
assert png_size(out + "/one/crash_rate.png") == (1000, 600)

def tables(md):
    """[(heading, [row cells...])]: every markdown table with the nearest heading above it"""
    found, heading, rows = [], "", None
    for line in md.splitlines() + [""]:
        if line.startswith("|"):
            if rows is None:
                rows = []
                found.append((heading, rows))
            if not re.match(r"^\|(-+\|)+$", line):
                rows.append([c.strip() for c in line.strip("|").split("|")])
        else:
            rows = None
            if line.startswith("#"):
                heading = line.lstrip("#").strip()
    return found

md = open(out + "/two/summary.md").read()
found = tables(md)
for c in controllers:
    pivot = [rows for heading, rows in found if heading == c]
    assert len(pivot) == 1, "no single pivot table for %s:\n%s" % (c, md)
    rows = pivot[0]
    assert rows[0] == ["payload_mass \\ at", "0.1", "0.3"], rows[0]
    assert [r[0] for r in rows[1:]] == ["0.08", "0.12"], rows
    for r in rows[1:]:
        assert len(r) == 3 and all(re.match(r"^\d+/3 \[", cell) for cell in r[1:]), r
binned = [rows for heading, rows in found if heading.startswith("Crash rate (and expect")]
assert len(binned) == 1 and binned[0][0] == ["bin"] + controllers, binned
for r in binned[0][1:]:  # no row rests on a single run of a controller
    assert all(int(re.match(r"^\d+/(\d+)", cell).group(1)) >= 2 for cell in r[1:]), r
assert max(len(rows[0]) for _, rows in found) <= 9, "a table wider than the group table"

md = open(out + "/one/summary.md").read()
binned = [rows for heading, rows in tables(md) if heading.startswith("Crash rate (and expect")]
assert len(binned) == 1 and len(binned[0][0]) == 5, binned  # bin + 2 controllers x 2 masses
assert "Crash rate per grid cell" not in md
print("panels: %d (two factors), %d (one factor); pivot tables for %s" %
      (len(two), len(one), ", ".join(controllers)))
PY
echo "sweep_grid_factors_test: $failures failure(s)"
[ "$failures" -eq 0 ]
