#!/bin/bash
# The add-on's library folder against the oldest glibc it must load on: libndfbake.so and every
# library beside it may need no glibc symbol version above <glibc> (objdump -T) and no libstdc++
# version at all (GLIBCXX_, CXXABI_): Blender on Rocky 8 or Ubuntu 20.04 has glibc 2.28 and
# whichever libstdc++ that system has.
# Usage: check_symbol_versions.sh <folder> <glibc>, e.g. 2.28
set -u
folder=$1 ceiling=GLIBC_$2
status=0
for file in "$folder"/*; do
    name=$(basename "$file")
    versions=$(objdump -T "$file" | grep -oE '\b(GLIBC|GLIBCXX|CXXABI)_[0-9.]+\b' | sort -uV)
    # The glibc versions sorting after the ceiling.
    newer=$( (grep '^GLIBC_' <<<"$versions"; echo "$ceiling") | sort -uV | sed "0,/^$ceiling\$/d")
    echo "$name: glibc versions $(grep '^GLIBC_' <<<"$versions" | tr '\n' ' ')"
    if [ -n "$newer" ]; then
        echo "FAIL: $name needs glibc newer than ${ceiling#GLIBC_}:"
        objdump -T "$file" | grep -wF "$newer" | sed 's/^/    /'
        status=1
    fi
    cxx=$(grep -E '^(GLIBCXX|CXXABI)_' <<<"$versions" | tr '\n' ' ')
    [ -z "$cxx" ] || { echo "FAIL: $name needs the host's libstdc++: $cxx"; status=1; }
done
[ $status = 0 ] && echo "PASS check_symbol_versions (glibc ${ceiling#GLIBC_})"
exit $status
