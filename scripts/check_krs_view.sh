#!/usr/bin/env bash
# The tests of examples/krs_view (ctest's example_krs_view_*), one case per call:
#
#   check_krs_view.sh CASE KRS_VIEW XVFB_RUN GLSL_EXPORT CHECK_VIEW_FRAME WORK_DIR
#
#   frame_SCENE  the viewer's headless frame of SCENE at 160 x 120 against glsl_export's CPU
#                reference of the same program: at least 99.5% of the pixels within 2/255 (check_view_frame)
#   bad_glsl     a --glsl file that does not compile: status 1 and the compiler's message,
#                naming the undeclared function, on stderr; no screenshot written
#   no_display   no DISPLAY and no virtual display: status 1 and the one line saying so
#   accumulate   a program red left of x = 8.5 and green below y = 4.5: the plain frame's pixel at
#                (8, 4) sees neither (its center is on both edges); 16 accumulated samples see each
#                edge over about half the pixel: 0.5 within 1/16 (the jitter's 15 Halton points and
#                the center split each axis evenly up to one sample), every other pixel unchanged
#   reload       the viewer started on a broken file and waiting (--exit-after-reload); once it has
#                reported the error the file is rewritten with a good program of one colour, and the
#                frame it writes must be that colour
#
# Every case but no_display runs the viewer under `xvfb-run -a` (a virtual X display; Mesa's
# llvmpipe draws there). Where xvfb-run was not found when CMake configured, the case fails and
# says so: it never passes without running.
set -uo pipefail

case_name="$1" view="$2" xvfb_run="$3" export="$4" check="$5" work="$6"
rm -rf "$work" && mkdir -p "$work"

fail() {
    echo "check_krs_view.sh $case_name: $*" >&2
    exit 1
}
need_xvfb() {
    [ -x "$xvfb_run" ] ||
        fail "xvfb-run was not found when CMake configured ('$xvfb_run'): run scripts/install-deps.sh --tests"
}
# The text of file $1 must contain $2.
must_say() {
    grep -qF -- "$2" "$1" || { cat "$1" >&2; fail "expected '$2' in $(basename "$1")"; }
}

case "$case_name" in
frame_*)
    need_xvfb
    scene="${case_name#frame_}"
    "$xvfb_run" -a "$view" --scene "$scene" --frames 2 --output "$work/view.png" \
        --width 160 --height 120 ||
        fail "krs_view --scene $scene failed"
    "$export" --scene "$scene" --reference "$work/reference.png" --width 160 --height 120 ||
        fail "glsl_export --scene $scene --reference failed"
    "$check" match "$work/view.png" "$work/reference.png" 99.5 ||
        fail "the viewer's frame is not the reference"
    ;;
bad_glsl)
    need_xvfb
    cat >"$work/broken.glsl" <<'EOF'
void mainImage(out vec4 fragColor, in vec2 fragCoord) {
    fragColor = krs_no_such_function(fragCoord);
}
EOF
    status=0
    "$xvfb_run" -a "$view" --glsl "$work/broken.glsl" --frames 2 --output "$work/view.png" \
        --width 32 --height 24 \
        >"$work/out.txt" 2>"$work/err.txt" || status=$?
    [ "$status" -eq 1 ] || { cat "$work/err.txt" >&2; fail "exit status $status, expected 1"; }
    must_say "$work/err.txt" "krs_view: cannot compile"
    must_say "$work/err.txt" "krs_no_such_function" # the compiler's own message names it
    must_say "$work/err.txt" ":2(" # on the file's line 2: the host's own lines are not counted
    [ ! -e "$work/view.png" ] || fail "a screenshot was written although nothing compiled"
    ;;
no_display)
    status=0
    env -u DISPLAY -u WAYLAND_DISPLAY "$view" --scene sponge --frames 1 \
        --output "$work/view.png" --width 16 --height 16 >"$work/out.txt" 2>"$work/err.txt" || status=$?
    [ "$status" -eq 1 ] || { cat "$work/err.txt" >&2; fail "exit status $status, expected 1"; }
    must_say "$work/err.txt" "krs_view: cannot open a window: "
    must_say "$work/err.txt" "; run under xvfb-run or with a display"
    [ "$(wc -l <"$work/err.txt")" -eq 1 ] ||
        { cat "$work/err.txt" >&2; fail "more than one line on stderr"; }
    ;;
accumulate)
    need_xvfb
    cat >"$work/edges.glsl" <<'EOF'
void mainImage(out vec4 c, in vec2 p) { c = vec4(p.x < 8.5 ? 1.0 : 0.0, p.y < 4.5 ? 1.0 : 0.0, 0.0, 1.0); }
EOF
    for run in plain accumulated; do
        flag=() && [ "$run" = accumulated ] && flag=(--accumulate)
        "$xvfb_run" -a "$view" --glsl "$work/edges.glsl" --frames 16 "${flag[@]}" \
            --output "$work/$run.png" --width 16 --height 8 || fail "krs_view ($run) failed"
    done
    "$check" coverage "$work/plain.png" 8 4 0 0 ||
        fail "the plain frame is not the program at the pixel centers"
    # 255 (1/2 -+ 1/16), rounded outward
    "$check" coverage "$work/accumulated.png" 8 4 111 144 ||
        fail "the accumulated frame is not the pixels' coverage"
    ;;
reload)
    need_xvfb
    printf 'void mainImage(out vec4 c, in vec2 p) { c = not_yet_written(p); }\n' >"$work/edited.glsl"
    "$xvfb_run" -a "$view" --glsl "$work/edited.glsl" --frames 2 --output "$work/view.png" \
        --width 32 --height 24 --exit-after-reload 30 >"$work/out.txt" 2>"$work/err.txt" &
    viewer=$!
    # Until the viewer has compiled (and refused) the broken file: then the good one is a change.
    for _ in $(seq 300); do
        grep -qF "not_yet_written" "$work/err.txt" 2>/dev/null && break
        kill -0 "$viewer" 2>/dev/null || break
        sleep 0.05
    done
    grep -qF "not_yet_written" "$work/err.txt" || {
        kill "$viewer" 2>/dev/null
        cat "$work/err.txt" >&2
        fail "the viewer never reported the broken file"
    }
    # Written whole and renamed over the file, as editors save: the viewer never reads half of it.
    # 0.2, 0.6, 0.4 are stored by an 8-bit framebuffer as 51, 153, 102.
    printf 'void mainImage(out vec4 c, in vec2 p) { c = vec4(0.2, 0.6, 0.4, 1.0); }\n' >"$work/good.tmp"
    mv "$work/good.tmp" "$work/edited.glsl"
    status=0
    wait "$viewer" || status=$?
    [ "$status" -eq 0 ] || { cat "$work/err.txt" >&2; fail "exit status $status, expected 0"; }
    must_say "$work/err.txt" "krs_view: reloaded"
    "$check" colour "$work/view.png" 51 153 102 ||
        fail "the frame is not the edited program's colour"
    ;;
*)
    echo "check_krs_view.sh: unknown case '$case_name'" >&2
    exit 2
    ;;
esac
echo "check_krs_view.sh $case_name: passed"
