#!/usr/bin/env bash
# Intel Open Image Denoise for pbgi's `denoise` feature. There is no Debian
# package: the library comes from PyPI's pyoidn wheel, unpacked into
# target/oidn. Prints the folder to give as OIDN_DIR (its lib/ holds
# libOpenImageDenoise.so); later runs reuse it.
#
#   export OIDN_DIR=$(scripts/oidn.sh)
#   cargo build --release --features denoise
#   target/release/pbgi render --denoise
set -euo pipefail
cd "$(dirname "$0")/.."
version=2.5.1.0
dir=$PWD/target/oidn
if [ ! -e "$dir/lib/libOpenImageDenoise.so" ]; then
    tmp=$(mktemp -d)
    trap 'rm -rf "$tmp"' EXIT
    python3 -m pip download --quiet --no-deps --only-binary=:all: -d "$tmp" "pyoidn==$version" >&2
    python3 - "$tmp" "$dir" <<'PY'
import glob, os, sys, zipfile
tmp, dest = sys.argv[1], sys.argv[2]
(wheel,) = glob.glob(os.path.join(tmp, "pyoidn-*.whl"))
prefix = "pyoidn/oidn/"
with zipfile.ZipFile(wheel) as z:
    for info in z.infolist():
        if info.filename.startswith(prefix) and not info.is_dir():
            out = os.path.join(dest, info.filename[len(prefix):])
            os.makedirs(os.path.dirname(out), exist_ok=True)
            with z.open(info) as src, open(out, "wb") as dst:
                dst.write(src.read())
            mode = info.external_attr >> 16
            if mode:
                os.chmod(out, mode & 0o777)
PY
    # The wheel keeps one file per name; the linker wants the bare one.
    [ -e "$dir/lib/libOpenImageDenoise.so" ] || ln -s libOpenImageDenoise.so.2 "$dir/lib/libOpenImageDenoise.so"
fi
echo "$dir"
