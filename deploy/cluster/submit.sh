#!/bin/bash
# Submits the sweep's job array, then its merge, held until every task of
# the array has ended. Run it from the repository's root.
set -eu
array=$(sbatch --parsable deploy/cluster/sweep.slurm)
# afterany, not afterok: a shard whose runs failed exits 1 with its record
# written, and the merged summary is where those failures are reported; a
# shard that wrote no record (a time limit) is named by the merge as
# missing. --parsable prints the job id, then `;cluster` on a federation.
sbatch --dependency=afterany:"${array%%;*}" deploy/cluster/merge.slurm
