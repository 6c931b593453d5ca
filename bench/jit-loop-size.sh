#!/bin/bash
# The size of the bounce loop in lavapipe's JIT code for a scene's trace shader: a measure
# of the shader's cost per ray that, unlike a timing, does not drift with the machine's
# load (llvmpipe runs both sides of every branch, so every instruction of the loop runs
# once per iteration). Renders the scene with the shader cache off, dumps the process's
# anonymous executable memory with gdb mid-render, disassembles it with objdump and
# reports the largest loop (the longest backward jump) and its commonest instructions.
#
# usage: bench/jit-loop-size.sh [SCENE] [WGTRACE]   (needs gdb and binutils)
# LOOPS=N also lists the N largest loops inside the bounce loop (the BVH walk's).
# defaults: bench/cornell.toml, target/release/wgtrace
set -euo pipefail
SCENE=${1:-bench/cornell.toml}
BIN=${2:-target/release/wgtrace}
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
MESA_SHADER_CACHE_DISABLE=1 WGTRACE_CACHE_DIR="$OUT/cache" \
    "$BIN" render "$SCENE" --spp 100000 -o "$OUT/image.exr" >"$OUT/render.log" 2>&1 &
PID=$!
sleep "${WAIT:-4}"
gdb -q -batch -p "$PID" -ex "python
for line in open('/proc/$PID/maps'):
    f = line.split()
    if f[1] == 'r-xp' and len(f) < 6:
        lo, hi = f[0].split('-')
        gdb.execute(f'dump memory $OUT/{lo}.bin 0x{lo} 0x{hi}')
" -ex detach >"$OUT/gdb.log" 2>&1
kill "$PID" 2>/dev/null || true
wait "$PID" 2>/dev/null || true
for f in "$OUT"/*.bin; do objdump -D -b binary -mi386:x86-64 "$f"; done >"$OUT/code.s"
python3 - "$OUT/code.s" <<'PY'
import bisect, collections, re, sys
ins = []
for line in open(sys.argv[1]):
    m = re.match(r'\s+([0-9a-f]+):\t[0-9a-f ]+\t(.*)', line)
    if m:
        ins.append((int(m.group(1), 16), m.group(2).strip()))
addrs = [a for a, _ in ins]
jumps = [(a, int(m.group(1), 16)) for a, t in ins
         for m in [re.match(r'j\w+\s+0x([0-9a-f]+)', t)] if m and int(m.group(1), 16) < a]
if not jumps:
    sys.exit("no loop found: did the render start within the wait?")
end, start = max(jumps, key=lambda j: j[0] - j[1])
body = ins[bisect.bisect_left(addrs, start):bisect.bisect(addrs, end)]
stack = sum(1 for _, t in body if re.search(r'\(%r[sb]p\)', t))
common = collections.Counter(t.split()[0] for _, t in body if t).most_common(8)
print(f"bounce loop: {len(body)} instructions, {stack} of them on the stack")
print("commonest: " + ", ".join(f"{k} {v}" for k, v in common))
# LOOPS=N: the N largest loops inside it too (the BVH walk's node and primitive loops)
inner = sorted({(e - s, s, e) for e, s in jumps if start <= s and e <= end and (s, e) != (start, end)}, reverse=True)
for _, s, e in inner[:int(__import__('os').environ.get('LOOPS', '0'))]:
    n = bisect.bisect(addrs, e) - bisect.bisect_left(addrs, s)
    print(f"inner loop at +{s - start:#x}: {n} instructions")
PY
