#!/usr/bin/env bash
# Run the sweep tests against a real single-node Slurm on this machine: bring it up
# (tools/slurm_single_node.sh, installing the Debian packages if needed), run the ignored tests
# of tests/sweep_slurm.rs, tear it down. Exit status: that of the tests, or 77 with a message
# ("SKIP: ...") when Slurm cannot be brought up here (no root, no apt-get, packages not
# installable, daemons not starting): a skip, not a pass.
#
#   tools/slurm_test.sh [extra cargo test arguments, e.g. --no-default-features]
set -uo pipefail
cd "$(dirname "$0")/.."
here=$(pwd)
tools/slurm_single_node.sh up
up=$?
if [ "$up" -ne 0 ]; then
    echo "SKIP: the Slurm sweep tests did not run (tools/slurm_single_node.sh up gave $up)" >&2
    exit 77
fi
trap '"$here"/tools/slurm_single_node.sh down' EXIT
cargo test --release "$@" --test sweep_slurm -- --ignored --test-threads 1
