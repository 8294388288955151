#!/usr/bin/env bash
# fresh-root.sh: does this commit install and configure on a brand-new Debian machine?
#
# The host has packages that earlier work installed, so a build here can pass while a new user's
# first command fails. This script keeps (once, cached) a `debootstrap --variant=minbase` root of
# $KRS_FRESH_SUITE (bookworm), copies it to a throwaway root for every run, puts the committed tree
# (git archive HEAD; uncommitted changes are NOT seen) at /root/krs, and runs in a chroot, as root
# with a clean environment:
#   --ci      (default) ./scripts/install-deps.sh --all, then a configure of every target (tests,
#             examples, benchmarks): what .ci/run checks before the suite, a few minutes
#   --readme  the README's two commands, ./scripts/examples.sh then CI=true ./scripts/test.sh
#             (2 cores: about an hour)
# It prints one verdict line per step with its wall time; a failed step prints the errors of its log
# (a configure error names the missing file or package) and the script exits 1.
#
# Needs: root on a Debian host whose apt sources reach a Debian mirror (read from
# /etc/apt/sources.list{,.d/*}, or set KRS_FRESH_MIRROR), git, debootstrap (installed when
# missing), ~8 GB free disk.
#
# Usage: scripts/fresh-root.sh [--ci|--readme] [--rebuild] [--keep]
#   --rebuild  debootstrap the cached pristine root again
#   --keep     keep this run's root (with its build trees) for inspection
# Environment: KRS_FRESH_ROOT cache directory (default /var/tmp/krs-fresh-root: pristine/ is the
#              cached root, run.<pid>/ a run's copy, logs/<mode>.<pid>/ its step logs);
#              KRS_FRESH_SUITE (bookworm);
#              KRS_FRESH_MIRROR (default: the host's).
set -euo pipefail

cache="${KRS_FRESH_ROOT:-/var/tmp/krs-fresh-root}"
suite="${KRS_FRESH_SUITE:-bookworm}"
mode=ci rebuild=0 keep=0
for arg in "$@"; do
    case "$arg" in
        --ci) mode=ci ;;
        --readme) mode=readme ;;
        --rebuild) rebuild=1 ;;
        --keep) keep=1 ;;
        -h | --help) sed -n '2,26p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
        *) echo "fresh-root.sh: unknown option '$arg' (use --ci, --readme, --rebuild, --keep)" >&2; exit 2 ;;
    esac
done
[ "$(id -u)" -eq 0 ] || { echo "fresh-root.sh: must run as root (debootstrap, chroot, mount)" >&2; exit 2; }
checkout="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && git rev-parse --show-toplevel)" ||
    { echo "fresh-root.sh: not inside a git checkout" >&2; exit 2; }

# The host's Debian mirror: the first URI of a one-line "deb" entry or a deb822 stanza whose suite is
# the host's own codename (never a third-party, -security or -updates entry).
host_mirror() {
    local codename
    # shellcheck source=/dev/null
    codename="$(. /etc/os-release && echo "${VERSION_CODENAME:-}")"
    { grep -hs '^[[:space:]]*deb[[:space:]]' /etc/apt/sources.list /etc/apt/sources.list.d/*.list |
        sed 's/\[[^]]*\]//' | awk -v s="$codename" '$3 == s { print $2 }'
      awk -v s="$codename" 'BEGIN { RS = "" }
        { u = ""; ok = 0
          for (i = 1; i <= NF; i++) { if ($i == "URIs:") u = $(i + 1); if ($i == s) ok = 1 }
          if (ok && u != "" && $0 !~ /Enabled:[[:space:]]*no/) print u }' /etc/apt/sources.list.d/*.sources 2>/dev/null
    } | head -n 1 || true # no *.list or *.sources file is no error: the caller says when none was found
}

# The pristine root is made once; .complete marks a debootstrap that finished (an interrupted one is
# made again). Runs may overlap (CI's --ci while someone runs --readme): a lock guards the making,
# and each run has its own copy and logs, named by its process id.
pristine="$cache/pristine" run="$cache/run.$$" logs="$cache/logs/$mode.$$"
mkdir -p "$cache"
exec 9> "$cache/.lock"
flock 9
if [ "$rebuild" -eq 1 ] || [ ! -e "$pristine/.complete" ]; then
    mirror="${KRS_FRESH_MIRROR:-$(host_mirror)}"
    [ -n "$mirror" ] || { echo "fresh-root.sh: no Debian mirror in the host's apt sources; set KRS_FRESH_MIRROR" >&2; exit 2; }
    command -v debootstrap >/dev/null || { apt-get update -q && apt-get install -y -q debootstrap; } >/dev/null
    echo "fresh-root.sh: debootstrap --variant=minbase $suite from $mirror into $pristine"
    rm -rf --one-file-system "$pristine"
    debootstrap --variant=minbase "$suite" "$pristine" "$mirror" > "$cache/debootstrap.log" 2>&1 ||
        { tail -n 20 "$cache/debootstrap.log"; echo "fresh-root.sh: debootstrap failed" >&2; exit 1; }
    touch "$pristine/.complete"
fi

# unmount_tree DIR: the mounts of a run's copy.
unmount_tree() {
    local m
    for m in dev sys proc; do
        if mountpoint -q "$1/$m"; then umount -R "$1/$m" || umount -R -l "$1/$m"; fi
    done
}
# What interrupted earlier runs left: copies whose process is gone (and the one shared copy of
# earlier versions of this script).
for old in "$cache"/run "$cache"/run.*; do
    [ -d "$old" ] || continue
    pid="${old##*/run.}"
    if [ "$old" = "$cache/run" ] || ! kill -0 "$pid" 2> /dev/null; then
        unmount_tree "$old"
        rm -rf --one-file-system "$old"
    fi
done
cp -a "$pristine" "$run" && rm -f "$run/.complete"
flock -u 9
# This run's copy; its mounts go away on any exit.
# shellcheck disable=SC2317 # called by the EXIT trap
cleanup() {
    unmount_tree "$run"
    if [ "$keep" -eq 0 ]; then rm -rf --one-file-system "$run"; else echo "fresh-root.sh: kept $run"; fi
}
trap cleanup EXIT
trap 'exit 130' INT TERM
cp -L /etc/resolv.conf "$run/etc/resolv.conf"
# The host's network trust, as its resolver and mirror: a host whose HTTPS goes through an
# inspecting proxy keeps the proxy's CA in /usr/local/share/ca-certificates, and without it npm's
# registry (install-deps.sh's `npm ci`) fails in the root with SELF_SIGNED_CERT_IN_CHAIN. The
# ca-certificates package, when install-deps.sh installs it, adds these to the root's bundle.
if compgen -G '/usr/local/share/ca-certificates/*.crt' >/dev/null; then
    mkdir -p "$run/usr/local/share/ca-certificates"
    cp -L /usr/local/share/ca-certificates/*.crt "$run/usr/local/share/ca-certificates/"
fi
mkdir -p "$run/root/krs" "$logs"
# The commit is fixed here: the verdict names what was tested, even if HEAD moves during the run.
commit="$(git -C "$checkout" rev-parse HEAD)"
git -C "$checkout" archive "$commit" | tar -x -C "$run/root/krs"
mount -t proc proc "$run/proc"
mount --rbind /sys "$run/sys" && mount --make-rslave "$run/sys"
mount --rbind /dev "$run/dev" && mount --make-rslave "$run/dev"

# step NAME COMMAND: runs COMMAND in the chroot as a new root login would, logs and times it. In --ci
# mode the configure is skipped after a failed install (it would only repeat the install's news).
failed=0 verdicts=()
step() {
    local name="$1" cmd="$2" start rc=0 secs verdict
    if [ "$failed" -ne 0 ] && [ "$mode" = ci ]; then verdicts+=("$(printf '%-14s %s' SKIPPED "$cmd")"); return; fi
    echo "fresh-root.sh: running '$cmd' (log: $logs/$name.log)"
    start=$(date +%s)
    env -i HOME=/root TERM=dumb PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
        chroot "$run" /bin/bash -lc "cd /root/krs && $cmd" > "$logs/$name.log" 2>&1 || rc=$?
    secs=$(($(date +%s) - start))
    if [ "$rc" -eq 0 ]; then verdict=PASS; else verdict="FAIL (exit $rc)"; failed=1; fi
    verdicts+=("$(printf '%-14s %-40s %dm%02ds  %s' "$verdict" "$cmd" $((secs / 60)) $((secs % 60)) "$logs/$name.log")")
    if [ "$rc" -ne 0 ]; then
        echo "fresh-root.sh: '$cmd' failed on a fresh $suite root; its errors:" >&2
        # CMake's and apt's own words name what is missing; the log's end shows where it stopped.
        grep -E -A 10 '^CMake Error|^E: |^fatal error|: error: ' "$logs/$name.log" | head -n 60 >&2 || true
        echo "--- last lines of $logs/$name.log:" >&2
        tail -n 15 "$logs/$name.log" >&2
    fi
}
all_targets="-DKRS_BUILD_TESTS=ON -DKRS_BUILD_EXAMPLES=ON -DKRS_BUILD_BENCHMARKS=ON"
case "$mode" in
    ci)
        step install-deps "./scripts/install-deps.sh --all"
        step configure "cmake -S . -B build -DCMAKE_BUILD_TYPE=Release $all_targets"
        ;;
    readme)
        step examples "./scripts/examples.sh"
        step test "CI=true ./scripts/test.sh"
        ;;
esac

echo "fresh-root.sh: $suite minbase, ${commit:0:7}, --$mode:"
printf '  %s\n' "${verdicts[@]}"
exit "$failed"
