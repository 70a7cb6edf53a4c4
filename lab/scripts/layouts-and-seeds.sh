# Sourced, after `cd` to the repository, by the scripts that sweep
# `"LAYOUT..." FROM..TO`: checks the two arguments, builds the release
# binary (or takes $UBF), and makes a scratch directory removed on exit. Sets `layouts`,
# `seeds`, `ubf` and `work`.
if [ $# -ne 2 ]; then
    echo "usage: $0 \"LAYOUT...\" FROM..TO   (e.g. \"2121 2222\" 100..130)" >&2
    exit 2
fi
layouts=$1 seeds=$2
# UBF names another binary to run (an earlier build, to compare against).
if [ -z "${UBF:-}" ]; then
    cargo build --release --quiet
fi
ubf=${UBF:-target/release/ubf}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
