#!/usr/bin/env bash
# Extracts the real normal maps of the receding-surface benchmark (examples/receding_bench.py) from
# Debian 12's packages into ${NDFBAKE_CACHE:-$HOME/.cache/ndfbake}/normal-maps, named by what they
# are. The packages are downloaded (apt-get download: no install, no dependencies), the five files
# taken out with dpkg-deb and the packages deleted again (1.3 GB of game data for five images).
# A map already there is kept. Run as root (apt-get download writes where it is run).
#
# Each is a tangent-space normal map made by others, used as its package ships it:
#   fabric     Red Eclipse, Torley's "cyberhandwoven": a coarse hand-woven cloth, 512²
#   carpet     Red Eclipse, jojo's carpet01: a fine pebbled pile, 512² (Debian 12 ships no leather
#              or skin map; this is the finest grain there is, as leather's)
#   aluminium  Qt 3D's examples, aluminium_random_brushed: brushed metal, 1024², 16-bit
#   stone      Cube 2 (Sauerbraten), gk's stone_ground: cobbled stone, 512²
#   walnut     Qt 3D's examples, american_walnut_crown_cut: wood grain, 1024², 16-bit
set -euo pipefail
out="${NDFBAKE_CACHE:-$HOME/.cache/ndfbake}/normal-maps"
maps=(
  "fabric.png redeclipse-data usr/share/games/redeclipse/data/torley/desat/cyberhandwoven_n.png"
  "carpet.png redeclipse-data usr/share/games/redeclipse/data/jojo/carpet01_n.png"
  "aluminium.png qt3d5-examples usr/lib/x86_64-linux-gnu/qt5/examples/qt3d/exampleresources/assets/textures/aluminium_random_brushed/aluminium_random_brushed_normal.png"
  "stone.png cube2-data usr/share/games/cube2/packages/gk/fantasy/stone_ground_gk_v01/stone_ground_gk_v01_nm.png"
  "walnut.png qt3d5-examples usr/lib/x86_64-linux-gnu/qt5/examples/qt3d/exampleresources/assets/textures/american_walnut_crown_cut/american_walnut_crown_cut_normal.png"
)
mkdir -p "$out"
declare -A wanted=()
for entry in "${maps[@]}"; do
  read -r name package path <<<"$entry"
  [ -s "$out/$name" ] || wanted[$package]+="$name:$path "
done
[ ${#wanted[@]} -eq 0 ] && { echo "normal maps: all in $out"; exit 0; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
apt-get update -qq || true   # a fresh machine's lists may be older than the archive
for package in "${!wanted[@]}"; do
  (cd "$work" && apt-get download -qq "$package" 2>/dev/null)
  deb=$(ls "$work"/"${package}"_*.deb)
  members=()
  for pair in ${wanted[$package]}; do members+=("./${pair#*:}"); done
  dpkg-deb --fsys-tarfile "$deb" | tar -x -C "$work" "${members[@]}"
  for pair in ${wanted[$package]}; do
    # The temporary name, then a rename: an interrupted run leaves no half-written map.
    cp "$work/${pair#*:}" "$out/.${pair%%:*}.part" && mv "$out/.${pair%%:*}.part" "$out/${pair%%:*}"
  done
  rm -f "$deb"
done
echo "normal maps: $(ls "$out" | tr '\n' ' ')in $out"
