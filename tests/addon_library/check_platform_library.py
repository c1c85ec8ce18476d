"""One platform's extension zip and the library in it, read with LLVM's tools (any object format).

    check_platform_library.py PLATFORM ZIP HEADER [--glibc 2.28] [--macos 11.0]

- The zip: its manifest names PLATFORM alone (Blender's spelling, windows-x64), and it carries
  that platform's library (ndfbake.dll, libndfbake.dylib, libndfbake.so) and no other's.
- Exports: exactly the functions ndfbake.h declares, nothing of the C++ runtime linked into it.
- Dependencies: the OS's own runtime only. Windows: KERNEL32 and the Universal CRT
  (api-ms-win-crt-*); macOS: libSystem alone, no weak binding (dyld would coalesce weak symbols
  with Blender's own libc++), LC_BUILD_VERSION minos = --macos, an ad-hoc code signature, the
  right CPU; Linux: glibc's libraries, no symbol version above --glibc, none of libstdc++.
Prints what it read and PASS, or every FAIL.
"""
import argparse
import re
import subprocess
import sys
import tempfile
import zipfile

LIBRARY_FILES = {"windows": "ndfbake.dll", "macos": "libndfbake.dylib", "linux": "libndfbake.so"}
ELF_MACHINES = {"x64": "x86-64", "arm64": "aarch64"}
MACHO_CPUS = {"x64": "X86_64", "arm64": "ARM64"}
# glibc's own libraries: every Linux system Blender runs on has them.
GLIBC_LIBRARIES = {"libc.so.6", "libm.so.6", "libpthread.so.0", "libdl.so.2", "librt.so.1",
                   "ld-linux-x86-64.so.2", "ld-linux-aarch64.so.1"}

failures = []


def fail(message):
    failures.append(message)
    print("FAIL:", message)


def tool(*args):
    return subprocess.run(args, check=True, capture_output=True, text=True).stdout


def api_functions(header):
    with open(header, encoding="utf-8") as f:
        text = f.read()
    # Every function the header marks NDFB_API: `NDFB_API <return type> ndfb_name(`.
    return set(re.findall(r"\bNDFB_API\b[^;(]*?\b(ndfb_\w+)\s*\(", text))


def version_tuple(text):
    return tuple(int(x) for x in text.split("."))


def check_windows(library):
    headers = tool("llvm-objdump", "-p", library)
    imports = set(re.findall(r"DLL Name: (\S+)", headers))
    print("imports:", " ".join(sorted(imports)))
    for dll in imports:
        if dll.upper() != "KERNEL32.DLL" and not dll.lower().startswith("api-ms-win-crt-"):
            fail("%s imports %s, which is neither KERNEL32 nor the Universal CRT" % (library, dll))
    # The export table's rows end with the symbol's name: "  ordinal  RVA  name".
    table = headers.split("Export Table:", 1)[1].split("\n\n", 1)[0] if "Export Table:" in headers else ""
    exports = set(re.findall(r"^\s+\d+\s+0x[0-9a-f]+\s+(\S+)$", table, re.M))
    machine = re.search(r"file format (\S+)", headers).group(1)
    if machine != "coff-x86-64":
        fail("%s is %s, not an x86-64 DLL" % (library, machine))
    return exports


def check_macos(library, arch, macos):
    exports = {name[1:] for name in tool("llvm-nm", "-gU", "--format=just-symbols", library).split()}
    used = tool("llvm-objdump", "--macho", "--dylibs-used", library).splitlines()[1:]
    used = [line.strip().split(" (")[0] for line in used]
    print("dylibs used:", " ".join(used))
    if used[:1] != ["@rpath/libndfbake.dylib"]:
        fail("install name is %s, not @rpath/libndfbake.dylib" % used[:1])
    for dylib in used[1:]:
        if dylib != "/usr/lib/libSystem.B.dylib":
            fail("%s links %s: only libSystem may be" % (library, dylib))
    weak = tool("llvm-objdump", "--macho", "--weak-bind", library).split("symbol", 1)[-1].split()
    if weak:
        fail("%s binds weakly to %s" % (library, " ".join(weak)))
    headers = tool("llvm-objdump", "--macho", "--private-headers", library)
    cpu = re.search(r"MH_MAGIC_64\s+(\S+)", headers)
    if not cpu or cpu.group(1) != MACHO_CPUS[arch]:
        fail("%s is built for %s, not %s" % (library, cpu and cpu.group(1), MACHO_CPUS[arch]))
    minos = re.search(r"cmd LC_BUILD_VERSION.*?minos (\S+)", headers, re.S)
    print("minimum macOS:", minos and minos.group(1))
    if not minos or version_tuple(minos.group(1)) != version_tuple(macos):
        fail("%s asks for macOS %s, not %s" % (library, minos and minos.group(1), macos))
    if "LC_CODE_SIGNATURE" not in headers:
        fail("%s carries no code signature (Apple silicon loads no unsigned code)" % library)
    else:
        print("code signature: present (ad-hoc)")
    return exports


def check_linux(library, arch, glibc):
    header = tool("llvm-readelf", "-h", library)
    machine = re.search(r"Machine:\s+(.*)", header).group(1)
    if ELF_MACHINES[arch] not in machine.lower().replace("_", "-"):
        fail("%s is %s, not %s" % (library, machine, ELF_MACHINES[arch]))
    dynamic = tool("llvm-readelf", "-d", library)
    needed = set(re.findall(r"\(NEEDED\)\s+Shared library: \[(.*)\]", dynamic))
    print("NEEDED:", " ".join(sorted(needed)))
    for name in needed - GLIBC_LIBRARIES:
        fail("%s needs %s, which is not glibc's" % (library, name))
    symbols = tool("llvm-readelf", "--dyn-syms", "-W", library)
    versions = set(re.findall(r"@+((?:GLIBC|GLIBCXX|CXXABI)_[\d.]+)", symbols))
    glibc_versions = sorted((v for v in versions if v.startswith("GLIBC_")),
                            key=lambda v: version_tuple(v[6:]))
    print("glibc versions:", " ".join(glibc_versions))
    for v in glibc_versions:
        if version_tuple(v[6:]) > version_tuple(glibc):
            fail("%s needs %s, newer than glibc %s" % (library, v, glibc))
    for v in sorted(versions - set(glibc_versions)):
        fail("%s needs the host's libstdc++ (%s)" % (library, v))
    exports = set()
    for line in symbols.splitlines():
        fields = line.split()
        # Num: Value Size Type Bind Vis Ndx Name: defined (Ndx not UND), global or weak.
        if len(fields) >= 8 and fields[4] in ("GLOBAL", "WEAK") and fields[6] != "UND":
            exports.add(fields[7].split("@")[0])
    return exports


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("platform")
    parser.add_argument("zip")
    parser.add_argument("header")
    parser.add_argument("--glibc", default="2.28")
    parser.add_argument("--macos", default="11.0")
    args = parser.parse_args()
    system, arch = args.platform.split("_")
    library_file = LIBRARY_FILES[system]

    with zipfile.ZipFile(args.zip) as z:
        names = z.namelist()
        manifest = z.read("blender_manifest.toml").decode("utf-8")
        platforms = re.findall(r"^platforms = \[(.*)\]", manifest, re.M)
        expected = '"%s"' % args.platform.replace("_", "-")
        print("manifest platforms:", platforms)
        if platforms != [expected]:
            fail("the manifest's platforms are %s, not [%s]" % (platforms, expected))
        for other in set(LIBRARY_FILES.values()) - {library_file}:
            if other in names:
                fail("the zip carries %s, another platform's library" % other)
        if library_file not in names:
            fail("the zip has no %s" % library_file)
            return 1
        work = tempfile.mkdtemp()
        library = z.extract(library_file, work)

    api = api_functions(args.header)
    if system == "windows":
        exports = check_windows(library)
    elif system == "macos":
        exports = check_macos(library, arch, args.macos)
    else:
        exports = check_linux(library, arch, args.glibc)
    print("exports: %d symbols, the header declares %d functions" % (len(exports), len(api)))
    for name in sorted(exports - api):
        fail("%s exports %s, which is not in ndfbake.h" % (library_file, name))
    for name in sorted(api - exports):
        fail("%s does not export %s" % (library_file, name))
    if failures:
        return 1
    print("PASS check_platform_library %s" % args.platform)
    return 0


if __name__ == "__main__":
    sys.exit(main())
