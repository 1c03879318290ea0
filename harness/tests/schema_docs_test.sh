#!/usr/bin/env bash
# The generated tables in docs/ are the binary's own output, never edited by hand:
# docs/schema.md is `hpa schema all`, and docs/design.md's rate table is
# `hpa schema rates scenarios/lissajous_T5.yaml`. A change regenerates them:
#   build/bin/hpa schema all > docs/schema.md
#   build/bin/hpa schema rates scenarios/lissajous_T5.yaml   (paste the table into design.md)
# usage: schema_docs_test.sh HPA_BIN SOURCE_DIR
set -uo pipefail
hpa=$1; src=$2
status=0
if ! diff -u "$src/docs/schema.md" <("$hpa" schema all); then
  echo "docs/schema.md differs from \`hpa schema all\` (above); regenerate it" >&2
  status=1
fi
while IFS= read -r line; do
  if ! grep -qxF -- "$line" "$src/docs/design.md"; then
    echo "docs/design.md lacks this row of \`hpa schema rates scenarios/lissajous_T5.yaml\`: $line" >&2
    status=1
  fi
done < <("$hpa" schema rates "$src/scenarios/lissajous_T5.yaml" | grep '^|')
[ $status -eq 0 ] && echo "docs/schema.md and design.md's rate table match the binary"
exit $status
