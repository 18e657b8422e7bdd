#!/usr/bin/env python3
"""cmz_header.py - read a .cmz header's needs, or write the file with one need changed (the header
and file CRCs made valid again), for the gates that lie to the decoders (docs/FORMAT.md, Header).

  cmz_header.py need FILE ID            print limit ID's need
  cmz_header.py set-need FILE ID VALUE OUT   write OUT: FILE with limit ID's need set to VALUE

Formats 1-3: the fixed header (u32 H at byte 8, u8 N at 16, need i the u32 at 60 + 4 i); format 4:
the compact header (varints from byte 6: H, flags, N, the N needs, ...; H counts its own varint, so
a need whose varint changes length moves everything after it and H itself).
"""
import struct
import sys
import zlib


def varint(b, at):
    v, shift = 0, 0
    while True:
        c = b[at]
        at += 1
        v |= (c & 0x7F) << shift
        shift += 7
        if not c & 0x80:
            return v, at


def put_varint(v):
    out = bytearray()
    while v >= 0x80:
        out.append((v & 0x7F) | 0x80)
        v >>= 7
    out.append(v)
    return bytes(out)


def needs(b):
    """(needs, span): the need values and, for format 4, the byte range of the fields after H."""
    if b[4] < 4:
        n = b[16]
        return [struct.unpack_from('<I', b, 60 + 4 * i)[0] for i in range(n)], None
    h, at = varint(b, 6)
    start = at
    _, at = varint(b, at)  # flags
    n, at = varint(b, at)
    vals = []
    for _ in range(n):
        v, at = varint(b, at)
        vals.append(v)
    return vals, (start, h)


def set_need(b, i, value):
    b = bytearray(b)
    if b[4] < 4:
        h = struct.unpack_from('<I', b, 8)[0]
        assert i < b[16]
        struct.pack_into('<I', b, 60 + 4 * i, value)
        struct.pack_into('<I', b, h - 4, zlib.crc32(bytes(b[:h - 4])))
    else:
        # re-emit the fields between H and the CRC with the one need changed, then H anew
        h, at = varint(b, 6)
        fields = []
        while at < h - 4:
            v, at = varint(b, at)
            fields.append(v)
        assert at == h - 4, 'header fields do not end at its CRC'
        assert i < fields[1], 'no such need'
        fields[2 + i] = value
        body = b''.join(put_varint(v) for v in fields)
        for lh in range(1, 6):
            nh = 6 + lh + len(body) + 4
            if len(put_varint(nh)) == lh:
                break
        head = bytes(b[:6]) + put_varint(nh) + body
        b = bytearray(head + struct.pack('<I', zlib.crc32(head)) + bytes(b[h:]))
    struct.pack_into('<I', b, len(b) - 4, zlib.crc32(bytes(b[:-4])))
    return bytes(b)


def main(argv):
    if len(argv) == 4 and argv[1] == 'need':
        vals, _ = needs(open(argv[2], 'rb').read())
        print(vals[int(argv[3])])
        return 0
    if len(argv) == 6 and argv[1] == 'set-need':
        out = set_need(open(argv[2], 'rb').read(), int(argv[3]), int(argv[4]))
        open(argv[5], 'wb').write(out)
        return 0
    sys.stderr.write(__doc__)
    return 2


if __name__ == '__main__':
    sys.exit(main(sys.argv))
