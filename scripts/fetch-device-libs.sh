#!/usr/bin/env bash
# Adds to .gl/ the Debian packages of the mesh libraries' runtime (assimp, Gmsh and what they
# load) that a GPU machine without Debian's libraries lacks; .gl/prelude.sh unpacks every
# package there. Libraries every Linux image has (libc, libstdc++, zlib, ...) stay out: they
# would replace the machine's own. Run once .gl/ holds the GL packages and its prelude.sh:
#   scripts/fetch-device-libs.sh [build/default/app/deformlab]
set -euo pipefail
cd "$(dirname "$0")/.."
binary=${1:-build/default/app/deformlab}
base='^(libc6|libgcc-s1|libstdc\+\+6|libgomp1|zlib1g|liblzma5|libzstd1|libbsd0|libmd0|libexpat1|libpng16-16|'
base+='libgl1|libglvnd0|libglx0|libopengl0|libegl1|libgles2|libglew2.2|libvulkan1)$'
packages=$(for lib in $(ldd "$binary" | awk '/=> \//{print $3}'); do
              dpkg -S "$(readlink -f "$lib")" 2>/dev/null | cut -d: -f1 || true
            done | sort -u | grep -Ev "$base")
mkdir -p .gl
(cd .gl && apt-get download -qq $packages)
du -ch .gl/*.deb | tail -1
