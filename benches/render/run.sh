#!/usr/bin/env bash
# The render benchmark: mvgrasp (wgpu on GL and Vulkan) against PyRender 0.1.45 (the seed
# paper's renderer, on EGL and OSMesa), same mesh, same 20 PhoXi S views (516 x 386), RGB +
# depth + mask read back, in the same run, on the same Mesa CPU driver (llvmpipe / lavapipe).
# Prints views per second, the ratios, and how well both depths agree.
#
#   benches/render/run.sh [MESH]
#
# MESH defaults to the YCB mustard bottle (16k faces) in shared/ beside the repository.
# Environment: ROUNDS (3) rounds of every renderer, interleaved so that both see the same load;
# REPEATS (5) timed calls per run after one warm-up; VIEWS (20); BACKENDS ("gl vulkan") for
# mvgrasp; PLATFORMS ("egl osmesa") for PyRender; BENCH_HARDWARE=1 to let Mesa use a GPU
# instead of forcing its CPU driver. Writes benches/render/out/ and benches/render/.venv/
# (both git-ignored). Needs python3 (3.11 tested), cargo, and Mesa's EGL/Vulkan drivers;
# installs libosmesa6 with apt-get when it is missing and this runs as root.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
mesh="${1:-$root/../shared/data/meshes/ycb/meshes/006_mustard_bottle_textured.obj}"
rounds="${ROUNDS:-3}"
repeats="${REPEATS:-5}"
views="${VIEWS:-20}"
backends="${BACKENDS:-gl vulkan}"
platforms="${PLATFORMS:-egl osmesa}"
venv="$here/.venv"
out="$here/out"

if [[ ! -f "$mesh" ]]; then
    echo "error: mesh not found: $mesh (pass a mesh path, or put shared/ beside the repository)" >&2
    exit 2
fi
mesh="$(cd "$(dirname "$mesh")" && pwd)/$(basename "$mesh")"

if [[ "${BENCH_HARDWARE:-0}" != 1 ]]; then
    # Same Mesa CPU rasteriser for both renderers even where a GPU is present.
    export LIBGL_ALWAYS_SOFTWARE=1
fi

# --- PyRender's virtual environment, made once (a marker tracks the pinned requirements). ---
requirements="$here/requirements.txt"
marker="$venv/.installed-$(sha256sum "$requirements" | cut -c1-16)"
if [[ ! -f "$marker" ]]; then
    echo "== creating $venv (pyrender and pinned dependencies)"
    started=$(date +%s%N)
    rm -rf "$venv"
    python3 -m venv "$venv"
    # --no-deps: pyrender pins PyOpenGL==3.1.0, whose OSMesa support is broken; 3.1.7 works.
    "$venv/bin/pip" install --quiet --disable-pip-version-check --no-deps -r "$requirements"
    touch "$marker"
    echo "== venv installed in $(( ($(date +%s%N) - started) / 1000000 )) ms"
fi
py="$venv/bin/python"

if [[ " $platforms " == *" osmesa "* ]] && ! ldconfig -p | grep -q 'libOSMesa\.so'; then
    if [[ "$(id -u)" == 0 ]] && command -v apt-get > /dev/null; then
        echo "== installing libosmesa6 (PyRender's OSMesa platform)"
        apt-get install -y -q libosmesa6 > /dev/null 2>&1 \
            || { apt-get update -q > /dev/null 2>&1 && apt-get install -y -q libosmesa6 > /dev/null 2>&1; } \
            || echo "warning: could not install libosmesa6; the OSMesa rows will be missing" >&2
    else
        echo "warning: libOSMesa not found (apt-get install libosmesa6); no OSMesa rows" >&2
    fi
fi

# --- mvgrasp's example, built once. ---
echo "== building the bench_render example (release)"
(cd "$root" && cargo build --release --quiet --example bench_render)
target_dir="${CARGO_TARGET_DIR:-$root/target}"
bench="$target_dir/release/examples/bench_render"

rm -rf "$out"
mkdir -p "$out"
cameras="$out/cameras.json"
log="$out/errors.log"
: > "$log"

# Runs one measurement into $out/NAME.json; a failure is reported and leaves no file.
measure() {
    local name="$1"
    shift
    if ! "$@" > "$out/$name.json" 2>> "$log"; then
        echo "   $name failed: $(grep -v XDG_RUNTIME_DIR "$log" | tail -n 1)" >&2
        rm -f "$out/$name.json"
        return 1
    fi
}

depth_ref=""
for round in $(seq 1 "$rounds"); do
    echo "== round $round of $rounds"
    for backend in $backends; do
        measure "r$round-mvgrasp-$backend" "$bench" --mesh "$mesh" --views "$views" \
            --repeats "$repeats" --backend "$backend" --cameras-out "$cameras" \
            --depth-out "$out/depth-$backend.npy" --json || continue
        [[ -n "$depth_ref" ]] || depth_ref="$out/depth-$backend.npy"
    done
    if [[ ! -f "$cameras" ]]; then
        echo "error: mvgrasp wrote no cameras; see $log" >&2
        exit 1
    fi
    for platform in $platforms; do
        args=(--mesh "$mesh" --cameras "$cameras" --repeats "$repeats" --json --no-fallback)
        if [[ "$round" == 1 && -n "$depth_ref" ]]; then
            args+=(--depth-ref "$depth_ref")
        fi
        measure "r$round-pyrender-$platform" env PYOPENGL_PLATFORM="$platform" \
            "$py" "$here/bench_pyrender.py" "${args[@]}" || true
    done
done

echo
"$py" "$here/report.py" "$out"
