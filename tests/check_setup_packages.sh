#!/usr/bin/env bash
# Does setup.sh install every Debian package that a build of this project used?
#
#   tests/check_setup_packages.sh BUILD_DIR
#
# BUILD_DIR is a configured and built tree. "Used" means any file under /usr or /lib that
#   - the configure step recorded in CMakeCache.txt (libraries, include dirs, package configs),
#   - a compiler read while building (every header in the *.o.d dependency files),
#   - a built program or library loads at run time (ldd),
#   - the build ran (cmake, the compiler, make).
# Each file is mapped to the package that owns it (dpkg -S; a directory owned by several packages
# is covered by any one of them). A file is covered when its owner is one of setup.sh's packages,
# one of their dependencies (recursively, as apt installs them with --no-install-recommends), or
# part of every Debian system (Essential, required, important). Prints what is not covered and
# exits 1: a fresh machine would fail to build. A file found under /usr/local or /opt also fails:
# it does not come from a Debian package at all.
set -uo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
build=${1:?usage: check_setup_packages.sh BUILD_DIR}
cache="$build/CMakeCache.txt"
[ -f "$cache" ] || { echo "no CMakeCache.txt in $build (configure and build first)" >&2; exit 2; }

# 1. Files the build used.
cache_paths() {
    sed -n 's/^[A-Za-z0-9_.-]*:\(FILEPATH\|PATH\|STRING\|INTERNAL\)=\(\/[^;]*\(;[^;]*\)*\)$/\2/p' \
        "$cache" | tr ';' '\n' | grep -E '^/(usr|lib|opt)/' | grep -v '^/usr/local$'
}
header_paths() {
    find "$build" -name '*.o.d' -print0 | xargs -0 -r cat | tr ' \\' '\n\n' |
        grep -E '^/(usr|lib|opt)/' | sed 's/:$//'
}
loaded_paths() {
    find "$build" -type f \( -perm -u+x -o -name '*.so*' \) ! -name '*.sh' |
        while read -r f; do [ "$(head -c4 "$f" | tr -d '\0')" = $'\x7fELF' ] && echo "$f"; done |
        xargs -r ldd 2>/dev/null | sed -n 's/.*=> \(\/[^ ]*\) .*/\1/p'
}
tool_paths() {
    for t in cmake ctest make "$(sed -n 's/^CMAKE_CXX_COMPILER:[A-Z]*=//p' "$cache")"; do
        command -v "$t"
    done
}
mapfile -t used < <({ cache_paths; header_paths; loaded_paths; tool_paths; } |
    while read -r p; do [ -e "$p" ] && echo "$p"; done | sort -u)
[ ${#used[@]} -gt 0 ] || { echo "found no files the build used in $build" >&2; exit 2; }

foreign=$(printf '%s\n' "${used[@]}" | grep -E '^/(usr/local|opt)/')
if [ -n "$foreign" ]; then
    echo "the build used files that no Debian package installs:"; echo "$foreign" | head -20
    exit 1
fi

# 2. Owners. dpkg knows a file under the name its package shipped it with; with Debian's merged
# /usr that may be /lib/... or /usr/lib/..., and a symlink's target may be the owned file.
# The spellings of every file, made in the shell (a process or two per file would take minutes).
declare -A owners spelled
mapfile -t resolved < <(printf '%s\0' "${used[@]}" | xargs -0 -r realpath -e --)
[ ${#resolved[@]} -eq ${#used[@]} ] || { echo "could not resolve the files the build used" >&2; exit 2; }
for i in "${!used[@]}"; do
    p=${used[$i]} r=${resolved[$i]} list=""
    for c in "$p" "$r" "${p#/usr}" "/usr$p" "${r#/usr}" "/usr$r"; do
        [[ $c == /* ]] || continue
        [[ $'\n'$list == *$'\n'$c$'\n'* ]] || list+=$c$'\n'  # once each
    done
    spelled[$p]=$list
done
mapfile -t candidates < <(printf '%s' "${spelled[@]}" | sort -u)
# dpkg's file lists, read once (dpkg -S matches every name against all of them: over a minute).
while IFS=$'\t' read -r path pkgs; do
    owners[$path]=$pkgs
done < <(printf '%s\n' "${candidates[@]}" | awk '
    FNR == NR { want[$0] = 1; next }
    ($0 in want) { pkg = FILENAME; sub(/.*\//, "", pkg); sub(/\.list$/, "", pkg); sub(/:.*/, "", pkg)
                   own[$0] = own[$0] " " pkg }
    END { for (f in own) print f "\t" substr(own[f], 2) }' - /var/lib/dpkg/info/*.list)

# 3. What setup.sh installs, with its dependencies, and what every Debian system has.
mapfile -t named < <(bash "$repo/setup.sh" packages)
covered=$( {
    apt-cache depends --recurse --installed --no-recommends --no-suggests --no-conflicts \
        --no-breaks --no-replaces --no-enhances "${named[@]}" 2>/dev/null |
        grep -v '^ ' | sed 's/^<\(.*\)>$/\1/' | cut -d: -f1
    dpkg-query -W -f='${Package} ${Priority} ${Essential}\n' |
        awk '$2=="required" || $2=="important" || $3=="yes" {print $1}'
} | sort -u)
declare -A is_covered
for pkg in $covered; do is_covered[$pkg]=1; done

# 4. Every used file must have an owner that is covered.
declare -A missing_pkgs=() used_pkgs=()
unowned=()
for p in "${used[@]}"; do
    found=""; ok=""
    while read -r s; do
        for pkg in ${owners[$s]:-}; do
            found=1
            [ -n "${is_covered[$pkg]:-}" ] || continue
            ok=1
            [ -d "$p" ] || used_pkgs[$pkg]=1
        done
    done <<<"${spelled[$p]%$'\n'}"
    if [ -z "$found" ]; then
        # Files that configure or the compiler generate (no package owns them) are only allowed
        # outside /usr/include and /usr/lib, where packages put what a build consumes.
        case "$p" in /usr/include/*|/usr/lib/*|/lib/*) unowned+=("$p") ;; esac
    elif [ -z "$ok" ]; then
        for s in ${spelled[$p]}; do
            for pkg in ${owners[$s]:-}; do missing_pkgs[$pkg]+="$p "; done
        done
    fi
done

status=0
if [ ${#missing_pkgs[@]} -gt 0 ]; then
    echo "the build used packages that setup.sh does not install:"
    for pkg in "${!missing_pkgs[@]}"; do
        echo "  $pkg (e.g. $(echo "${missing_pkgs[$pkg]}" | cut -d' ' -f1))"
    done
    status=1
fi
if [ ${#unowned[@]} -gt 0 ]; then
    echo "the build used files that no installed package owns:"
    printf '  %s\n' "${unowned[@]}" | head -20
    status=1
fi
if [ $status -eq 0 ]; then
    echo "setup.sh covers the ${#used_pkgs[@]} packages whose files the build used" \
        "(${#used[@]} files and directories)"
fi
exit $status
