#!/usr/bin/env bash
# docs/schema.md is `hpa schema all`: the registries' own words, never edited by hand. A new
# controller, estimator, event type, expect key or metric regenerates it:
#   build/bin/hpa schema all > docs/schema.md
# usage: schema_docs_test.sh HPA_BIN DOCS_SCHEMA_MD
set -uo pipefail
if ! diff -u "$2" <("$1" schema all); then
  echo "docs/schema.md differs from \`hpa schema all\` (above); regenerate it:" >&2
  echo "  build/bin/hpa schema all > docs/schema.md" >&2
  exit 1
fi
echo "docs/schema.md matches hpa schema all"
