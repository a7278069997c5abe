#!/usr/bin/env bash
# Run by Snakemake once, inside the new conda environment, from the workflow's working
# directory (the repository): install ballimpact itself, its dependencies coming from conda.
set -euo pipefail
python -m pip install --no-deps --no-build-isolation "${BALLIMPACT_SOURCE:-.}"
