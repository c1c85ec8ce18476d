#!/bin/bash
# The add-on's library folder (native/addon in the build) against the issue's rule: libndfbake.so
# and every library beside it need only the allowed runtime libraries or libraries in the folder,
# libndfbake.so finds them through RUNPATH $ORIGIN, and the folder holds nothing else.
# Usage: check_runtime_dependencies.sh <folder> <allowed soname>...
set -u
folder=$1; shift
allowed=" $* "
status=0
fail() { echo "FAIL: $*"; status=1; }

[ -f "$folder/libndfbake.so" ] || { echo "FAIL: no $folder/libndfbake.so"; exit 1; }
runpath=$(readelf -d "$folder/libndfbake.so" | sed -n 's/.*(RUNPATH).*\[\(.*\)\]/\1/p')
[ "$runpath" = '$ORIGIN' ] || fail "libndfbake.so has RUNPATH '$runpath', expected \$ORIGIN"
readelf -d "$folder/libndfbake.so" | grep -q '(RPATH)' && fail "libndfbake.so has an RPATH"

for file in "$folder"/*; do
    name=$(basename "$file")
    [ "$name" = libndfbake.so ] || readelf -d "$file" | grep -q "(SONAME).*\[$name\]" ||
        fail "$name is not a library under its SONAME"
    for needed in $(readelf -d "$file" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p'); do
        if [[ "$allowed" == *" $needed "* ]]; then continue; fi
        [ -f "$folder/$needed" ] || fail "$name needs $needed, neither allowed nor bundled"
    done
    echo "$name: NEEDED $(readelf -d "$file" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p' | tr '\n' ' ')"
done
[ $status = 0 ] && echo "PASS check_runtime_dependencies"
exit $status
