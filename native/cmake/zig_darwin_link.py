"""Links a macOS dylib with LLVM's ld64.lld from what zig would link.

zig's own Mach-O linker ignores -exported_symbols_list, so a dylib it links exports libc++abi's
operator new/delete and binds weakly to them: inside Blender, dyld would then coalesce them with
Blender's own libc++. ld64.lld honours the list. zig still does the hard part: run with
ZIG_VERBOSE_LINK=1 it prints the link it would make (our objects, the libc++, libc++abi and
compiler-rt archives it built for the target, -lSystem); this script reruns that link with
ld64.lld, the exported-symbols list, an @rpath install name and an ad-hoc signature.

zig's libSystem.tbd lists the arm64e.x1 slices of newer SDKs, which Debian's lld 14 does not
parse; a copy without them (and with arm64e read as arm64, the slice a plain arm64 dylib binds
to) is written into --work.

    zig_darwin_link.py --ld64 LD64 --arch ARCH --macos VERSION --exports FILE --work DIR -- ZIG_CXX ARGS... -o OUT ...
"""
import argparse
import os
import re
import shlex
import subprocess
import sys


def sanitized_libsystem(zig_lib_dir, work):
    source = os.path.join(zig_lib_dir, "libc", "darwin", "libSystem.tbd")
    with open(source, encoding="utf-8") as f:
        text = f.read()
    text = re.sub(r",\s*arm64e\.x1-(?:macos|maccatalyst)", "", text)
    text = re.sub(r"arm64e\.x1-(?:macos|maccatalyst),\s*", "", text)
    text = text.replace("arm64e-", "arm64-")
    sdk = os.path.join(work, "sdk")
    os.makedirs(sdk, exist_ok=True)
    with open(os.path.join(sdk, "libSystem.tbd"), "w", encoding="utf-8") as f:
        f.write(text)
    return sdk


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--ld64", required=True)
    parser.add_argument("--arch", required=True)
    parser.add_argument("--macos", required=True)
    parser.add_argument("--exports", required=True)
    parser.add_argument("--work", required=True)
    parser.add_argument("command", nargs=argparse.REMAINDER)
    args = parser.parse_args()
    command = args.command[1:] if args.command[:1] == ["--"] else args.command
    output = command[command.index("-o") + 1]
    os.makedirs(args.work, exist_ok=True)

    # zig's own link, to a scratch file, printing what it links.
    scratch = os.path.join(args.work, "zig-linked.dylib")
    zig_command = list(command)
    zig_command[zig_command.index("-o") + 1] = scratch
    result = subprocess.run(zig_command, env=dict(os.environ, ZIG_VERBOSE_LINK="1"),
                            capture_output=True, text=True)
    if result.returncode != 0:
        sys.stderr.write(result.stdout + result.stderr)
        return result.returncode
    lines = [l for l in result.stderr.splitlines() if l.startswith("zig ld ")]
    if not lines:
        sys.stderr.write(result.stderr + "\nzig_darwin_link.py: zig printed no link line\n")
        return 1
    zig_args = shlex.split(lines[-1])[2:]

    # Its inputs and options, minus what ld64.lld is told here or would reject.
    link = []
    skip = 0
    for arg in zig_args:
        if skip:
            skip -= 1
            continue
        if arg == "-o":
            skip = 1
        elif arg == "-platform_version":
            skip = 3
        elif arg in ("-install_name", "-exported_symbols_list"):
            skip = 1
        else:
            link.append(arg)

    import ziglang  # this script runs in zig's venv
    sdk = sanitized_libsystem(os.path.join(os.path.dirname(ziglang.__file__), "lib"), args.work)
    arch = {"aarch64": "arm64", "arm64": "arm64", "x86_64": "x86_64"}[args.arch]
    ld64 = [args.ld64, "-arch", arch, "-platform_version", "macos", args.macos, args.macos,
            "-install_name", "@rpath/" + os.path.basename(output),
            "-exported_symbols_list", args.exports, "-adhoc_codesign", "-L" + sdk,
            "-o", output] + link
    result = subprocess.run(ld64)
    os.remove(scratch)
    return result.returncode


if __name__ == "__main__":
    sys.exit(main())
