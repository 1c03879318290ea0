#!/usr/bin/env bash
# Every relative link in README.md and docs/*.md points at a file of the repository, and no page
# refers to a design document outside it.
# usage: docs_links_test.sh SOURCE_DIR
set -uo pipefail
cd "$1" || exit 2
python3 - <<'PY'
import glob, os, re, sys
pages = ["README.md"] + sorted(glob.glob("docs/*.md")) + sorted(glob.glob("*/README.md"))
bad = []
for page in pages:
    text = open(page).read()
    for m in re.finditer(r"\]\(([^)#\s]+)(#[^)]*)?\)", text):
        target = m.group(1)
        if target.startswith(("http://", "https://", "mailto:")):
            continue
        if not os.path.exists(os.path.join(os.path.dirname(page), target)):
            bad.append(f"{page}: broken link {target}")
    if "DESIGN.md" in text or "../shared" in text:
        bad.append(f"{page}: refers to a document outside the repository")
print("\n".join(bad) or f"{len(pages)} pages, every link resolves")
sys.exit(1 if bad else 0)
PY
