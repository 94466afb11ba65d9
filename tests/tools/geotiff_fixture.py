#!/usr/bin/env python3
# geotiff_fixture.py rot|ft OUT.tif: a 5 x 5 float32 GeoTIFF written byte by byte
# (no GDAL tools needed): "rot" with a rotated ModelTransformation in UTM
# 32N; "ft" in NAD83 / California zone 3 (ftUS) with heights in US survey
# feet. For the georeferencing warnings of cli_cases.sh (gis_warnings).
import struct, sys
def tiff(fn, w, h, vals, tags_extra):
    data = struct.pack('<%df' % (w * h), *vals)
    tags = {256: (4, [w]), 257: (4, [h]), 258: (3, [32]), 259: (3, [1]), 262: (3, [1]), 273: (4, [0]),
            277: (3, [1]), 278: (4, [h]), 279: (4, [len(data)]), 339: (3, [3])}
    tags.update(tags_extra)
    n = len(tags)
    ifd_size = 2 + 12 * n + 4
    extra = b''
    base = 8 + ifd_size
    entries = b''
    fmt = {3: 'H', 4: 'I', 12: 'd'}
    sizes = {3: 2, 4: 4, 12: 8}
    data_off = None
    blobs = []
    for tag in sorted(tags):
        t, v = tags[tag]
        raw = struct.pack('<%d%s' % (len(v), fmt[t]), *v)
        if len(raw) <= 4:
            entries += struct.pack('<HHI', tag, t, len(v)) + raw.ljust(4, b'\0')
        else:
            entries += struct.pack('<HHII', tag, t, len(v), base + len(extra))
            extra += raw
            if len(extra) % 2: extra += b'\0'
    data_off = base + len(extra)
    # patch strip offset
    out = bytearray(b'II*\0' + struct.pack('<I', 8) + struct.pack('<H', n) + entries + b'\0\0\0\0' + extra + data)
    i = 8 + 2
    for tag in sorted(tags):
        if tag == 273:
            struct.pack_into('<I', out, i + 8, data_off)
        i += 12
    open(fn, 'wb').write(out)
kind = sys.argv[1]
vals = [float((i % 5) * 3 + i // 5) for i in range(25)]
if kind == 'rot':
    # a projected CRS (UTM 32N) and a rotated transform: 20 m pixels turned
    keys = [1, 1, 0, 3, 1024, 0, 1, 1, 1025, 0, 1, 1, 3072, 0, 1, 32632]
    tiff(sys.argv[2], 5, 5, vals, {34264: (12, [20, 5, 0, 400000, 5, -20, 0, 5100000, 0, 0, 1, 0, 0, 0, 0, 1]),
                                   34735: (3, keys)})
else:
    # NAD83 / California zone 3 (ftUS), heights in US survey feet (9003)
    keys = [1, 1, 0, 4, 1024, 0, 1, 1, 1025, 0, 1, 1, 3072, 0, 1, 2227, 4099, 0, 1, 9003]
    tiff(sys.argv[2], 5, 5, vals, {33550: (12, [3, 3, 0]), 33922: (12, [0, 0, 0, 6000000, 2000000, 0]),
                                   34735: (3, keys)})
