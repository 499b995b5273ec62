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
OCCUPIED_HUES = {(235, 120, 40), (200, 40, 40), (150, 90, 30), (220, 60, 160), (230, 185, 30), (140, 50, 150),
                 (90, 150, 50), (250, 100, 100)}


def figure_size(dims, rows, title=True):
    """Size of a segmentation.png as docs/cli.md lays it out, for a map of dims (nx, ny, nz) and
    `rows` volumes: four z slices (every z when nz < 4), then a y and an x slice when nz > 1."""
    nx, ny, nz = dims
    m = max(dims)
    shrink = (m + 639) // 640
    scale = min(8, max(1, 256 // m))
    px = lambda n: (n + shrink - 1) // shrink * scale
    panels = [(px(nx), px(ny))] * (4 if nz >= 4 else nz)  # (width, height) of z slices
    if nz > 1:
        panels += [(px(nx), px(nz)), (px(ny), px(nz))]
    width = 6 + sum(w + 6 for w, _ in panels)
    width = max(width, 470)
    height = 6 + (14 if title else 0) + rows * (10 + max(h for _, h in panels) + 6) + 22
    return width, height
