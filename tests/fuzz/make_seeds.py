#!/usr/bin/python3
"""Writes the seed corpora of tests/fuzz/corpus/ that are not copies of
shipped files (small PNGs, NPYs, bridge datagram streams, differential
cases). Run from the repository root; deterministic. The scenario seeds are
the shipped scenarios (copied by hand: cp scenarios/*.yaml
tests/fuzz/corpus/scenario/)."""
import random
import struct
import zlib

import numpy as np

ROOT = 'tests/fuzz/corpus'


def chunk(kind, data):
    return struct.pack('>I', len(data)) + kind + data + struct.pack('>I', zlib.crc32(kind + data) & 0xffffffff)


def png(w, h, depth, ctype, raw, extra=b''):
    ihdr = struct.pack('>IIBBBBB', w, h, depth, ctype, 0, 0, 0)
    return (b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', ihdr) + extra + chunk(b'IDAT', zlib.compress(raw)) +
            chunk(b'IEND', b''))


def rows(w, h, bits, channels):
    row_bytes = (w * bits * channels + 7) // 8
    return b''.join(b'\x00' + bytes(random.randrange(256) for _ in range(row_bytes)) for _ in range(h))


def tail(a, b):
    # The PNG target's last two bytes: the resampled size; b's bit 0 clear = CRCs repaired.
    return bytes([a, b])


def write(folder, files):
    for name, data in files.items():
        with open(f'{ROOT}/{folder}/{name}', 'wb') as f:
            f.write(data)


random.seed(1)
lying = (b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', 65536, 16384, 8, 0, 0, 0, 0)) +
         chunk(b'IDAT', zlib.compress(b'\x00' * 10)) + chunk(b'IEND', b''))
write('png', {
    'grey8_4x3.png': png(4, 3, 8, 0, rows(4, 3, 8, 1)) + tail(2, 4),
    'grey16_5x5.png': png(5, 5, 16, 0, rows(5, 5, 16, 1)) + tail(9, 10),
    'grey1_9x2.png': png(9, 2, 1, 0, rows(9, 2, 1, 1)) + tail(3, 2),
    'grey2_3x3.png': png(3, 3, 2, 0, rows(3, 3, 2, 1)) + tail(1, 0),
    'grey4_6x1.png': png(6, 1, 4, 0, rows(6, 1, 4, 1)) + tail(5, 6),
    'rgb8_3x2.png': png(3, 2, 8, 2, rows(3, 2, 8, 3)) + tail(4, 4),
    'rgba16_2x2.png': png(2, 2, 16, 6, rows(2, 2, 16, 4)) + tail(1, 2),
    'greya8_2x3.png': png(2, 3, 8, 4, rows(2, 3, 8, 2)) + tail(2, 2),
    'palette_4x4.png': png(4, 4, 8, 3, rows(4, 4, 8, 1), chunk(b'PLTE', bytes(i % 256 for i in range(768)))) + tail(7, 8),
    'constant_8x8.png': png(8, 8, 8, 0, b''.join(b'\x00' + b'\x80' * 8 for _ in range(8))) + tail(3, 6),
    'lying_header_65536x16384.png': lying + tail(0, 0),
    'bad_crc.png': png(4, 3, 8, 0, rows(4, 3, 8, 1))[:-1] + b'\x00' + tail(2, 1),
    'truncated.png': png(16, 16, 8, 0, rows(16, 16, 8, 1))[:60] + tail(2, 0),
})


def npy(arr, version=(1, 0), fortran=False):
    header = "{'descr': '%s', 'fortran_order': %s, 'shape': %s, }" % (
        arr.dtype.descr[0][1], 'True' if fortran else 'False', str(tuple(arr.shape)))
    fixed = 10 if version[0] == 1 else 12
    header += ' ' * ((64 - (fixed + len(header) + 1) % 64) % 64) + '\n'
    size = struct.pack('<H' if version[0] == 1 else '<I', len(header))
    return b'\x93NUMPY' + bytes(version) + size + header.encode() + arr.tobytes()


a = np.arange(12, dtype='<f4').reshape(3, 4)
huge = "{'descr': '<f4', 'fortran_order': False, 'shape': (2147483647, 2147483647), }"
write('npy', {
    'f4_3x4.npy': npy(a), 'f4_v2.npy': npy(a, (2, 0)), 'f4_v3.npy': npy(a, (3, 0)),
    'big_endian.npy': npy(a.astype('>f4')), 'empty_0x5.npy': npy(np.zeros((0, 5), '<f4')),
    'f8_wrong_dtype.npy': npy(a.astype('<f8')), 'fortran.npy': npy(a, fortran=True),
    'one_dim.npy': npy(np.arange(5, dtype='<f4')), 'truncated.npy': npy(a)[:-7],
    'huge_shape.npy': b'\x93NUMPY\x01\x00' + struct.pack('<H', 118) + (huge.ljust(117) + '\n').encode(),
})

MAGIC = 0x42484354


def packet(kind, session, seq, ts, payload, version=1):
    head = struct.pack('<IHHIIQII', MAGIC, version, kind, session, seq, ts, len(payload), 0) + payload
    return head + struct.pack('<I', zlib.crc32(head) & 0xffffffff)


def pose(x, y, z):
    return struct.pack('<7dII', x, y, z, 1, 0, 0, 0, 0, 1)


FORCE = struct.pack('<3dII', 1.0, 2.0, 3.0, 0, 7)


def stream(datagrams):
    # The bridge target's framing: [length][control] + bytes (control 0: as they are).
    return b''.join(bytes([len(d), 0]) + d for d in datagrams)


p1, p2 = packet(1, 5, 1, 1000, pose(0.1, 0.2, 0.3)), packet(1, 5, 2, 2000, pose(0.1, 0.2, 0.3))
p4 = packet(1, 5, 4, 3000, pose(float('nan'), 0, 0))
write('bridge', {
    'in_order.bin': stream([p1, p2, p4]),
    'duplicate_reordered.bin': stream([p2, p2, p1, p4]),
    'new_session.bin': stream([p1, packet(1, 6, 0, 10, pose(1, 1, 1)), p2]),
    'stale.bin': stream([p2, packet(1, 5, 3, 1500, pose(0, 0, 0))]),
    'wrap.bin': stream([packet(1, 1, 0xffffffff, 1, pose(0, 0, 0)), packet(1, 1, 0, 2, pose(0, 0, 0))]),
    'force.bin': stream([packet(2, 1, 1, 1, FORCE)]),
    'broken.bin': stream([p1[:50], p1 + b'x', b'XXXX' + p1[4:], packet(1, 5, 1, 1, pose(0, 0, 0), version=2),
                          p1[:-1] + b'\x00', packet(3, 5, 1, 1, pose(0, 0, 0)), packet(1, 5, 1, 1, FORCE), p1[:3]]),
    # Control 1: well-formed poses made by the target (session, sequence, time steps).
    'generated.bin': bytes([8, 1, 0, 1, 0, 5, 0, 0, 0, 0, 8, 1, 0, 255, 0, 5, 0, 0, 0, 0,
                            8, 1, 4, 2, 255, 0, 0, 0, 0, 0, 8, 1, 0, 1, 200, 0, 0, 0, 0, 0,
                            8, 3, 0, 1, 2, 0, 0, 0, 0, 0]),
})

# Differential: [cols, rows, origin, flags, den, 8 coordinates, 2 heights, terrain...].
random.seed(7)
cases = {}
for i, flags in enumerate([0, 1, 2, 3, 6, 7, 10, 11, 18, 35, 22, 39, 16, 33]):
    cases[f'case{i:02d}.bin'] = bytes([8, 6, i, flags, i % 3] + [random.randrange(256) for _ in range(58)])
write('differential', cases)
