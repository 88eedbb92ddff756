"""Makes bunny.off from CGAL's copy of the Stanford bunny (see SOURCE.md): moves it into the unit cube
(centred at (0.5, 0.5, 0.5), its longest side 0.8) and decimates it to TRIANGLES triangles by quadric
error (the fast-simplification package).

    python3 -m pip install numpy fast-simplification
    python3 decimate.py .../data/meshes/bunny00.off bunny.off 16000
"""
import sys
import numpy as np
import fast_simplification

def read_off(path):
    with open(path) as f:
        tokens = f.read().split()
    assert tokens[0] == "OFF"
    nv, nf = int(tokens[1]), int(tokens[2])
    i = 4
    v = np.array(tokens[i:i + 3 * nv], dtype=np.float64).reshape(nv, 3)
    i += 3 * nv
    faces = []
    for _ in range(nf):
        k = int(tokens[i]); faces.append([int(t) for t in tokens[i + 1:i + 1 + k]]); i += 1 + k
    assert all(len(f) == 3 for f in faces)
    return v, np.array(faces, dtype=np.int64)

src, dst, target = sys.argv[1], sys.argv[2], int(sys.argv[3])
v, f = read_off(src)
print("input", v.shape, f.shape, v.min(0), v.max(0))
# Into the unit cube: centred at (0.5, 0.5, 0.5), the longest side 0.8 (as the reconstruction protocol's shapes).
lo, hi = v.min(0), v.max(0)
v = (v - (lo + hi) / 2) * (0.8 / (hi - lo).max()) + 0.5
vd, fd = fast_simplification.simplify(v.astype(np.float32), f.astype(np.int32), target_count=target)
print("output", vd.shape, fd.shape)
with open(dst, "w") as out:
    out.write(f"OFF\n{len(vd)} {len(fd)} 0\n")
    for p in vd:
        out.write(f"{p[0]:.6g} {p[1]:.6g} {p[2]:.6g}\n")
    for t in fd:
        out.write(f"3 {t[0]} {t[1]} {t[2]}\n")
