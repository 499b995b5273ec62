"""A small PNG decoder (struct + zlib, no imaging library) for checking occseg's pictures:
verifies the signature and every chunk's CRC, undoes the scanline filters and returns the pixels."""
import struct
import zlib

SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _paeth(a, b, c):
    p = a + b - c
    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
    if pa <= pb and pa <= pc:
        return a
    return b if pb <= pc else c


def read_png(path):
    """Returns (width, height, rows): rows[y][x] is an (r, g, b) tuple. 8-bit greyscale, RGB,
    palette and RGBA images without interlacing (what occseg writes and more)."""
    data = open(path, "rb").read()
    assert data[:8] == SIGNATURE, f"{path}: not a PNG signature"
    pos, ihdr, palette, idat, seen_end = 8, None, None, b"", False
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos:pos + 4])
        kind, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + length]
        (crc,) = struct.unpack(">I", data[pos + 8 + length:pos + 12 + length])
        assert zlib.crc32(kind + body) & 0xFFFFFFFF == crc, f"{path}: bad CRC in {kind!r}"
        if kind == b"IHDR":
            ihdr = struct.unpack(">IIBBBBB", body)
        elif kind == b"PLTE":
            palette = [tuple(body[i:i + 3]) for i in range(0, len(body), 3)]
        elif kind == b"IDAT":
            idat += body
        elif kind == b"IEND":
            seen_end = True
            break
        pos += 12 + length
    assert ihdr and seen_end, f"{path}: missing IHDR or IEND"
    width, height, depth, colour, _, _, interlace = ihdr
    assert depth == 8 and interlace == 0, f"{path}: depth {depth}, interlace {interlace}"
    channels = {0: 1, 2: 3, 3: 1, 6: 4}[colour]
    stride = width * channels
    raw = zlib.decompress(idat)
    assert len(raw) == height * (stride + 1), f"{path}: {len(raw)} bytes of image data"
    rows, prev = [], bytearray(stride)
    for y in range(height):
        start = y * (stride + 1)
        f, line = raw[start], bytearray(raw[start + 1:start + 1 + stride])
        if f == 1:
            for i in range(channels, stride):
                line[i] = (line[i] + line[i - channels]) & 0xFF
        elif f == 2:
            for i in range(stride):
                line[i] = (line[i] + prev[i]) & 0xFF
        elif f == 3:
            for i in range(stride):
                left = line[i - channels] if i >= channels else 0
                line[i] = (line[i] + ((left + prev[i]) >> 1)) & 0xFF
        elif f == 4:
            for i in range(stride):
                left = line[i - channels] if i >= channels else 0
                up_left = prev[i - channels] if i >= channels else 0
                line[i] = (line[i] + _paeth(left, prev[i], up_left)) & 0xFF
        else:
            assert f == 0, f"{path}: filter type {f} in row {y}"
        if colour == 3:
            rows.append([palette[i] for i in line])
        elif colour == 0:
            rows.append([(v, v, v) for v in line])
        else:
            rows.append([tuple(line[i:i + 3]) for i in range(0, stride, channels)])
        prev = line
    return width, height, rows


def colours(rows):
    """The set of colours used."""
    out = set()
    for r in rows:
        out.update(r)
    return out


# occseg's state colours (tools/occseg/render_png.cpp, documented in docs/cli.md).
FREE = (150, 200, 255)
UNKNOWN = (245, 245, 245)
INK = (30, 30, 30)
# The palette of occupied segments (adapters/include/occseg/segment_colour.hpp, docs/cli.md).
SEGMENT_PALETTE = [(235, 120, 40), (200, 40, 40), (150, 90, 30), (220, 60, 160), (230, 185, 30), (140, 50, 150),
                   (90, 150, 50), (250, 100, 100), (30, 130, 130), (50, 70, 170), (170, 170, 40), (120, 210, 110),
                   (110, 70, 220), (240, 150, 200), (130, 30, 70), (160, 220, 60)]
OCCUPIED_HUES = set(SEGMENT_PALETTE)


def segment_colour(segment_id):
    """The colour of occupied segment `segment_id`: palette[(id * 2654435761 mod 2^32) >> 16 mod 16]."""
    return SEGMENT_PALETTE[(((segment_id * 2654435761) & 0xFFFFFFFF) >> 16) % 16]


def shade(c, f):
    """A colour scaled by f, each channel rounded down (render::shade)."""
    return tuple(int(v * f) for v in c)


def darker(c):
    return tuple(int(v * 0.55) for v in c)


# scene.png (tools/occseg/render_scene.hpp, docs/cli.md "The 3D picture").
SCENE_SIZE = (960, 720)
SCENE_VIEW = (6, 30, 700, 640)  # x, y, width, height
SCENE_FACES = (1.0, 0.80, 0.62)  # top, front (-y), left (-x)


def scene_shades(segment_id):
    return {shade(segment_colour(segment_id), f) for f in SCENE_FACES}


def scene_projection(box_lo, box_hi):
    """(scale, u0, v0, project) of scene.png for the occupied box [lo, hi) in voxel units, as
    docs/cli.md states it; project(x, y, z) gives the pixel (u, v)."""
    import math
    a, e = math.radians(30), math.radians(35)
    R = (math.cos(a), -math.sin(a), 0.0)
    U = (math.sin(a) * math.sin(e), math.cos(a) * math.sin(e), math.cos(e))
    us, vs = [], []
    for i in range(8):
        p = [box_hi[k] if i >> k & 1 else box_lo[k] for k in range(3)]
        us.append(sum(p[k] * R[k] for k in range(3)))
        vs.append(-sum(p[k] * U[k] for k in range(3)))
    vx, vy, vw, vh = SCENE_VIEW
    s = min((vw - 24) / (max(us) - min(us)), (vh - 24) / (max(vs) - min(vs)), 96)
    u0 = vx + vw / 2 - s * (min(us) + max(us)) / 2
    v0 = vy + vh / 2 - s * (min(vs) + max(vs)) / 2

    def project(x, y, z):
        return (u0 + s * (x * R[0] + y * R[1] + z * R[2]), v0 - s * (x * U[0] + y * U[1] + z * U[2]))
    return s, u0, v0, project


LEGEND_TEXT = {"free": "free", "unknown": "unknown", "occupied": "occupied",
               "segments": "occupied: one colour per segment", "boundary": "boundary",
               "empty_column": "top view: no occupied voxel (lower is darker)", "probability": "p 0 to 1"}
LEGEND_SWATCH = {"segments": 48, "probability": 102}


def _wrap(text, max_width):
    chars = max(1, max_width // 6)
    lines, line = [], ""
    for word in [w for w in text.split(" ") if w]:
        while len(word) > chars:
            if line:
                lines.append(line)
                line = ""
            lines.append(word[:chars])
            word = word[chars:]
        if not line:
            line = word
        elif len(line) + 1 + len(word) <= chars:
            line += " " + word
        else:
            lines.append(line)
            line = word
    if line:
        lines.append(line)
    return lines


def figure_layout(dims, row_titles, title, ideal=False, yx=None):
    """Layout of a segmentation.png as docs/cli.md describes it, for a map of dims (nx, ny, nz)
    and rows titled `row_titles` (map, segments[, ideal state]): four z slices (every z when
    nz < 4), then a y and an x slice (at yx = (y, x), default the middle) and the top view when
    nz > 1. Returns a dict: width, height, title lines [(text, x, y)], captions [(text, x, y)],
    columns [x], rows [y of the panels], panels [(w, h)] per column, legend [(kind, x, y)]."""
    nx, ny, nz = dims
    m = max(dims)
    shrink = (m + 639) // 640
    scale = min(8, max(1, 256 // m))
    px = lambda n: (n + shrink - 1) // shrink * scale
    if nz >= 4:
        slices = [("z = %d" % ((2 * k + 1) * nz // 8), px(nx), px(ny)) for k in range(4)]
    else:
        slices = [("z = %d" % z, px(nx), px(ny)) for z in range(nz)]
    if nz > 1:
        y, x = yx if yx else (ny // 2, nx // 2)
        slices += [("y = %d" % y, px(nx), px(nz)), ("x = %d" % x, px(ny), px(nz)), ("top view", px(nx), px(ny))]
    col_w = [max(w, 6 * len(c) + 6) for c, w, _ in slices]
    content = 6 + sum(w + 6 for w in col_w)
    kinds = ["free", "unknown"] + (["occupied"] if ideal else []) + ["segments", "boundary"]
    kinds += (["empty_column"] if nz > 1 else []) + ["probability"]
    item_w = lambda k: LEGEND_SWATCH.get(k, 10) + 4 + 6 * len(LEGEND_TEXT[k])
    width = max([content, 160] + [item_w(k) + 12 for k in kinds] + [6 * len(t) + 12 for t in row_titles])
    out = {"width": width, "title": [], "captions": [], "columns": [], "rows": [], "legend": [],
           "panels": [(w, h) for _, w, h in slices]}
    y = 6
    if title:
        for line in _wrap(title, width - 12):
            out["title"].append((line, 6, y))
            y += 10
        y += 4
    x = 6
    for (c, _, _), w in zip(slices, col_w):
        out["captions"].append((c, x, y))
        out["columns"].append(x)
        x += w + 6
    y += 14
    row_h = max(h for _, _, h in slices)
    for _ in row_titles:
        y += 10
        out["rows"].append(y)
        y += row_h + 6
    x, ly = 6, y + 2
    for k in kinds:
        w = item_w(k)
        if x > 6 and x + w > width - 6:
            x, ly = 6, ly + 14
        out["legend"].append((k, x, ly))
        x += w + 10
    out["height"] = ly + 14 + 6
    return out


def figure_size(dims, rows, title="occseg segment map.npy"):
    """Size of a segmentation.png (figure_layout) with `rows` volumes (2: map, segments; 3: and the
    ideal state)."""
    titles = ["map", "segments", "ideal state"][:rows]
    L = figure_layout(dims, titles, title, ideal=rows == 3)
    return L["width"], L["height"]
