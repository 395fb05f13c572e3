# Sourced by the bench scripts that run bip: from the project root, a release build of
# bip in $BIP and a scratch directory in $WORK, removed on exit.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
cargo build --release -q
BIP=$PWD/target/release/bip
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
