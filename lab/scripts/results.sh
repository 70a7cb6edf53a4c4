#!/usr/bin/env bash
# Regenerates both results pages from their runs, in one command:
# docs/results.md (every command it reports, with the ablation's builds of
# earlier commits) and docs/aiding-families.md (the experiment of
# lab/protocol.md). A few hours on two cores, most of them the ablation.
#
#   lab/scripts/results.sh
set -euo pipefail
cd "$(dirname "$0")/../.."
ABLATION=1 lab/scripts/results-data.sh
lab/scripts/aiding-families.sh "40001 40002 40003 40004 40005 40006 40007 40008 40009 40010 40011 40012" \
    50000..50030 > out/aiding-families.json
python3 lab/scripts/results-page.py
python3 lab/scripts/aiding-families-page.py
