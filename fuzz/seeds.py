#!/usr/bin/env python3
"""Writes the seed inputs of the fuzz targets (fuzz/seeds/<target>/seed-*).

    python3 fuzz/seeds.py

Seeds are small valid inputs in each target's layout (see fuzz/src/harness.rs), so that the
fuzzer starts from the deep paths (a solved pose, a parsed model) and mutates from there. The
COLMAP seeds are a subset (two images, their first observed 3D points) of the bundled model
data/colmap-boxes.
"""
import math
import os
import random
import struct

ROOT = os.path.dirname(os.path.abspath(__file__))
CORPUS = os.path.join(ROOT, "seeds")


def quarter(v):
    """Encoding 0..=2 of Reader::f64: (low - 16) / 4 with low in 0..32 (tag < 96)."""
    low = int(round(v * 4 + 16))
    assert 0 <= low < 32, v
    return bytes([low])


def i16(v):
    """Encoding 5: i16 / 256 (tag 0xa0)."""
    return bytes([0xA0]) + struct.pack("<h", int(round(v * 256)))


def raw(v):
    """Encoding 4: raw f64 bits (tag 0x80)."""
    return bytes([0x80]) + struct.pack("<d", v)


def problem(rng, n, project=True, planar=False, weighted=False, tile=None, special=None):
    flags = (1 if project else 0) | (2 if weighted else 0) | (8 if tile else 0)
    out = bytes([flags, n])
    if tile:
        out += struct.pack("<H", tile - 1)
    world = []
    for _ in range(n):
        x = [rng.uniform(-2, 2), rng.uniform(-2, 2), 0.0 if planar else rng.uniform(-2, 2)]
        world.append(x)
        out += b"".join(i16(v) for v in x)
    if project:
        rv = [rng.uniform(-3, 3) for _ in range(3)]
        t = [rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), rng.uniform(6, 10)]
        out += b"".join(i16(v) for v in rv + t)
        for _ in range(n):
            out += quarter(rng.choice([0.0, 0.25, -0.5])) + quarter(0.0)
    else:
        for _ in range(n):
            out += i16(rng.uniform(-1, 1)) + i16(rng.uniform(-1, 1))
    out += i16(0.5) + i16(-0.25) + i16(0.125)  # tiling offset
    if weighted:
        out += b"".join(quarter(rng.choice([0.25, 1.0, 2.0, 0.0])) for _ in range(n))
    if special is not None:
        out = out[:special] + bytes([0x64]) + out[special + 1 :]  # SPECIAL[4] = NaN
    return out


def write(target, name, data):
    d = os.path.join(CORPUS, target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, "seed-" + name), "wb") as f:
        f.write(data)


SEP = b"\0\0\xff"


def colmap_subset():
    src = os.path.join(ROOT, "..", "data", "colmap-boxes")
    cams = {}
    for line in open(os.path.join(src, "cameras.txt")):
        if line.startswith("#") or not line.strip():
            continue
        f = line.split()
        cams[int(f[0])] = (f[1], int(f[2]), int(f[3]), [float(v) for v in f[4:]])
    lines = [l for l in open(os.path.join(src, "images.txt")) if not l.startswith("#")]
    points = {}
    for line in open(os.path.join(src, "points3D.txt")):
        if line.startswith("#") or not line.strip():
            continue
        f = line.split()
        points[int(f[0])] = [float(v) for v in f[1:4]]
    images = []
    for k in range(2):
        head = lines[2 * k].split()
        obs = lines[2 * k + 1].split()
        kept = []
        for j in range(0, len(obs), 3):
            pid = int(obs[j + 2])
            if pid >= 0:
                kept.append((float(obs[j]), float(obs[j + 1]), pid))
            if len(kept) == 12:
                break
        images.append((head, kept))
    used_cams = sorted({int(h[8]) for h, _ in images})
    used_pts = sorted({p for _, kept in images for (_, _, p) in kept})
    # Text.
    ct = "# cameras\n" + "".join(
        f"{c} {cams[c][0]} {cams[c][1]} {cams[c][2]} {' '.join(map(str, cams[c][3]))}\n"
        for c in used_cams
    )
    it = "# images\n"
    for head, kept in images:
        it += " ".join(head) + "\n" + " ".join(f"{x} {y} {p}" for x, y, p in kept) + "\n"
    pt = "# points\n" + "".join(
        f"{p} {points[p][0]} {points[p][1]} {points[p][2]} 128 128 128 0.5 1 0\n" for p in used_pts
    )
    text = ct.encode() + SEP + it.encode() + SEP + pt.encode()
    # Binary (COLMAP's layout: little-endian, model ids).
    model_id = {"SIMPLE_RADIAL": 2, "PINHOLE": 1, "SIMPLE_PINHOLE": 0, "RADIAL": 3, "OPENCV": 4}
    cb = struct.pack("<Q", len(used_cams))
    for c in used_cams:
        name, w, h, params = cams[c]
        cb += struct.pack("<iiQQ", c, model_id[name], w, h) + struct.pack(f"<{len(params)}d", *params)
    ib = struct.pack("<Q", len(images))
    for head, kept in images:
        ib += struct.pack("<I", int(head[0]))
        ib += struct.pack("<7d", *[float(v) for v in head[1:8]])
        ib += struct.pack("<I", int(head[8]))
        ib += " ".join(head[9:]).encode() + b"\0"
        ib += struct.pack("<Q", len(kept))
        for x, y, p in kept:
            ib += struct.pack("<ddq", x, y, p)
    pb = struct.pack("<Q", len(used_pts))
    for p in used_pts:
        pb += struct.pack("<Q3d3Bd", p, *points[p], 128, 128, 128, 0.5)
        pb += struct.pack("<Q", 1) + struct.pack("<II", 1, 0)
    return text, cb + SEP + ib + SEP + pb


def colmap_write_seeds(text, binary):
    """The colmap_write target: both boxes subsets, plus models that stress the writer: numbers
    at the ends of the f64 range, a NaN point error, a 3D point id above i64::MAX (text only),
    image names that text cannot hold (binary only)."""
    write("colmap_write", "boxes-subset-text", text)
    write("colmap_write", "boxes-subset-binary", binary)
    cams = "1 PINHOLE 640 480 1e300 5e-324 -0 0.1\n2 SIMPLE_RADIAL 10 10 2.5 0 0 -1e-300\n"
    imgs = (
        "7 1 -0 0 5e-324 1e300 -1e-300 0.30000000000000004 1 name with  two  spaces\n"
        "1e-7 -0 18446744073709551615 0.5 0.5 -1 1e16 3 3\n"
        "8 0 0 0 1 0 0 0 2 a\n"
        "\n"
    )
    pts = (
        "18446744073709551615 -0 5e-324 1e16 255 0 7 NaN 7 0\n"
        "3 1.7976931348623157e308 -2.2250738585072014e-308 1 1 2 3 inf 7 1 8 0\n"
    )
    write("colmap_write", "extremes-text", cams.encode() + SEP + imgs.encode() + SEP + pts.encode())
    # Binary: names with a newline, leading and trailing spaces, and an empty name.
    cb = struct.pack("<Q", 1) + struct.pack("<iiQQ", 1, 0, 100, 100) + struct.pack("<3d", 50.0, 50.0, 50.0)
    ib = struct.pack("<Q", 3)
    for iid, name in [(1, b"two\nlines"), (2, b" padded "), (3, b"")]:
        ib += struct.pack("<I7dI", iid, 1.0, 0.0, -0.0, 0.0, 0.5, -0.25, 4.0, 1) + name + b"\0"
        ib += struct.pack("<Q", 1) + struct.pack("<ddq", 10.0, 20.0, 5)
    pb = struct.pack("<Q", 1) + struct.pack("<Q3d3Bd", 5, 0.0, 0.0, 1.0, 1, 2, 3, float("nan"))
    pb += struct.pack("<Q", 1) + struct.pack("<II", 1, 0)
    write("colmap_write", "names-binary", cb + SEP + ib + SEP + pb)


def cli_seeds(rng):
    def project(world):
        f, cx, cy = 800.0, 320.0, 240.0
        out = []
        for x, y, z in world:
            zc = z + 6.0
            out.append((f * x / zc + cx, f * y / zc + cy))
        return out

    world = [[rng.uniform(-1, 1) for _ in range(3)] for _ in range(8)]
    px = project(world)
    csv = "x,y,X,Y,Z\n" + "".join(
        f"{u:.4f},{v:.4f},{X:.4f},{Y:.4f},{Z:.4f}\n" for (u, v), (X, Y, Z) in zip(px, world)
    )
    js = (
        '{"camera": {"model": "PINHOLE", "params": [800, 800, 320, 240]},\n'
        + ' "points2d": ['
        + ", ".join(f"[{u:.4f}, {v:.4f}]" for u, v in px)
        + "],\n"
        + ' "points3d": ['
        + ", ".join(f"[{X:.4f}, {Y:.4f}, {Z:.4f}]" for X, Y, Z in world)
        + "]}\n"
    )
    # mode byte: bits 0-1 extension (0 json, 1 csv, 2 txt, 3 none), bit 2: camera line first.
    write("cli_input", "csv", bytes([1 | 4]) + b"PINHOLE 800 800 320 240\n" + csv.encode())
    write("cli_input", "csv-radial", bytes([3 | 4]) + b"SIMPLE_RADIAL 800 320 240 0.05\n" + csv.encode())
    write("cli_input", "json", bytes([0]) + js.encode())
    write("cli_input", "json-noext", bytes([3]) + js.encode())

    # CSV dialects (the csv crate's path): byte-order mark, quotes, `;` and tab delimiters,
    # columns in another order, CRLF, comments and blank lines; then a few malformed ones.
    bom = "\ufeff".encode()
    cam = b"PINHOLE 800 800 320 240\n"
    rows = [(u, v, X, Y, Z) for (u, v), (X, Y, Z) in zip(px, world)]

    def dialect(delim, quote="", order=(0, 1, 2, 3, 4), eol="\n"):
        names = ["x", "y", "X", "Y", "Z"]
        line = lambda vals: delim.join(f"{quote}{vals[k]}{quote}" for k in order) + eol
        return line(names) + "".join(line([f"{v:.4f}" for v in r]) for r in rows)

    write("cli_input", "csv-bom", bytes([1 | 4]) + cam + bom + csv.encode())
    write("cli_input", "csv-quoted", bytes([1 | 4]) + cam + dialect(",", '"').encode())
    write(
        "cli_input",
        "csv-semicolon",
        bytes([1 | 4]) + cam + dialect(";", '"', order=(2, 3, 4, 0, 1)).encode(),
    )
    write(
        "cli_input",
        "csv-tab-crlf-noext",
        bytes([3 | 4]) + cam + bom + dialect("\t", order=(4, 1, 0, 3, 2), eol="\r\n").encode(),
    )
    lines = dialect(", ").splitlines()
    commented = "\n".join(
        ["# exported", ""] + lines[:1] + ["  # indented", "\t"] + lines[1:4] + ["", "#x,y"] + lines[4:]
    )
    write("cli_input", "csv-comments", bytes([1 | 4]) + cam + commented.encode() + b"\n")
    write("cli_input", "json-bom", bytes([3]) + bom + js.encode())
    # Malformed: header only; a quoted field spanning lines; a control character; a mixed
    # header.
    write("cli_input", "bad-header-only", bytes([1 | 4]) + cam + b'"x";"y";"X";"Y";"Z"\n\n')
    head, first, *rest = dialect(";", '"').split("\n")
    first = ";".join(f if k != 1 else '"1\n2"' for k, f in enumerate(first.split(";")))
    write("cli_input", "bad-quoted-newline", bytes([1 | 4]) + cam + "\n".join([head, first] + rest).encode())
    write("cli_input", "bad-control", bytes([1 | 4]) + cam + dialect("\t").replace(".", "\x01", 1).encode())
    write("cli_input", "bad-header-mixed", bytes([1 | 4]) + cam + b"x,y;X\tY,Z\n1,2;3\t4,5\n")
    # Control characters echoed by the other input modes' errors (escaped, not raw): a JSON
    # unknown key, camera model and string value with escaped control characters, a raw one
    # in a JSON string, and a `--camera` argument with them in the model and a parameter.
    write("cli_input", "bad-json-key-control",
          bytes([0]) + js.replace('"points2d"', '"points\\u00012d"', 1).encode())
    write("cli_input", "bad-json-model-control",
          bytes([0]) + js.replace('"PINHOLE"', '"PIN\\u001bHOLE"', 1).encode())
    write("cli_input", "bad-json-raw-control",
          bytes([3]) + js.replace('"PINHOLE"', '"PIN\x07HOLE"', 1).encode())
    write("cli_input", "bad-json-value-control",
          bytes([2]) + js.replace("[800, 800", '["8\\u000700", 800', 1).encode())
    write("cli_input", "bad-camera-model-control", bytes([1 | 4]) + b"PIN\x1bHOLE 800 800 320 240\n" + csv.encode())
    write("cli_input", "bad-camera-param-control", bytes([0 | 4]) + b"PINHOLE 800 8\x0700 320 240\n" + js.encode())


def main():
    rng = random.Random(7)
    seeds = {
        "n4": problem(rng, 4),
        "n6": problem(rng, 6),
        "n10": problem(rng, 10),
        "planar6": problem(rng, 6, planar=True),
        "planar10": problem(rng, 10, planar=True),
        "weighted8": problem(rng, 8, weighted=True),
        "direct7": problem(rng, 7, project=False),
        "tiled1000": problem(rng, 10, tile=100),
        "tiled10000": problem(rng, 10, tile=1000),
        "nan": problem(rng, 6, special=5),
    }
    for name, p in seeds.items():
        for cfg, b in [("default", 0), ("algebraic", 1), ("exhaustive", 2)]:
            write("solve", f"{name}-{cfg}", bytes([b]) + p)
        # ransac: solver byte, threshold, confidence, fx, fy, seed, max_iter/4, lo, min_iter,
        # final factor, then the problem.
        opts = (
            bytes([0])
            + i16(4.0)
            + raw(0.999)
            + i16(100.0)
            + i16(100.0)
            + bytes([3, 25, 1, 20])
            + i16(2.0)
        )
        write("ransac", name, opts + p)
    text, binary = colmap_subset()
    write("colmap_text", "boxes-subset", text)
    write("colmap_binary", "boxes-subset", binary)
    colmap_write_seeds(text, binary)
    cli_seeds(rng)


if __name__ == "__main__":
    main()
