#!/usr/bin/env bash
# Installs what builds the Blender add-on's library for glibc 2.28 (native/addon_library): zig's
# clang and LLVM libc++ (PyPI's ziglang) in a venv, and the Debian sources of zlib, Imath (its
# half) and the OpenEXR core, at the versions of this system's -dev packages, unpacked with
# Debian's patches. Everything goes under NDFBAKE_ADDON_TOOLCHAIN_DIR (default
# ~/.cache/ndfbake/addon-toolchain), where native/CMakeLists.txt looks; a second run only
# refreshes what changed. Needs python3-venv and dpkg-dev (install-deps.sh installs both).
set -euo pipefail
dir=${NDFBAKE_ADDON_TOOLCHAIN_DIR:-$HOME/.cache/ndfbake/addon-toolchain}
zig_version=0.17.1
mkdir -p "$dir/sources"

if [ "$("$dir/venv/bin/python" -m ziglang version 2>/dev/null)" != "$zig_version" ]; then
  rm -rf "$dir/venv"
  /usr/bin/python3 -m venv "$dir/venv"  # Debian's, whatever Python manager is on PATH
  "$dir/venv/bin/pip" install -q "ziglang==$zig_version"
fi

# deb-src entries for exactly the archives apt already uses (their URIs, suites and components, in
# apt's order), kept in a private apt state under $dir: the system's sources and lists stay as
# they are, and nothing here needs root.
apt_dir=$dir/apt
mkdir -p "$apt_dir/lists/partial" "$apt_dir/cache/archives/partial"
apt-get indextargets --format 'deb-src $(REPO_URI) $(RELEASE) $(COMPONENT)' 'Created-By: Packages' |
  awk '!seen[$0]++' >"$apt_dir/sources.list"
apt_options=(-o "Dir::Etc::SourceList=$apt_dir/sources.list" -o Dir::Etc::SourceParts=/nonexistent
             -o "Dir::State::Lists=$apt_dir/lists" -o "Dir::Cache=$apt_dir/cache"
             -o "APT::Sandbox::User=$(id -un)")  # downloads as this user, into folders it owns
updated=false

# The source package of each -dev package, at the installed version: the add-on library then
# writes its EXRs with the code the full library uses.
for dev_package in zlib1g-dev libimath-dev libopenexr-dev; do
  source=$(dpkg-query -W -f '${source:Package}' "$dev_package")
  version=$(dpkg-query -W -f '${source:Version}' "$dev_package")
  [ "$(cat "$dir/sources/$source.version" 2>/dev/null)" = "$version" ] && continue
  if ! $updated; then apt-get -qq "${apt_options[@]}" update; updated=true; fi
  download=$(mktemp -d)
  (cd "$download" && apt-get -qq "${apt_options[@]}" source --download-only "$source=$version")
  rm -rf "$dir/sources/$source"
  dpkg-source --no-check -x "$download"/*.dsc "$dir/sources/$source" >/dev/null
  rm -rf "$download" "$dir/sources/${source}_"*  # dpkg-source leaves the upstream tarball beside
  echo "$version" >"$dir/sources/$source.version"
  echo "install-addon-toolchain: $source $version in $dir/sources/$source"
done
echo "install-addon-toolchain: zig $zig_version and sources ready in $dir"
