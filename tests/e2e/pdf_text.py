"""Text of a PDF written by Qt, for tests: the content streams' glyph codes
mapped through each font's ToUnicode table (stdlib only; enough for QPdfWriter's
output, not a general PDF reader)."""

from __future__ import annotations

import re
import zlib


def _objects(b):
    return {int(m.group(1)): m.start(1) for m in re.finditer(rb'(?m)^(\d+) 0 obj', b)}


def _stream(b, start):
    m = re.compile(rb'stream\r?\n').search(b, start)
    head = b[start:m.start()]
    end = b.find(b'endstream', m.end())
    data = b[m.end():end]
    if b'/FlateDecode' not in head:
        return head, data.rstrip(b'\r\n')
    # the end-of-line before "endstream" is not part of the data, but the
    # compressed bytes may themselves end in CR or LF: let zlib find its end
    return head, zlib.decompressobj().decompress(data)


def _u(h):
    return bytes.fromhex(h.decode()).decode('utf-16-be')


def _cmap(text):
    table = {}
    for blk in re.findall(rb'beginbfchar(.*?)endbfchar', text, re.S):
        for src, dst in re.findall(rb'<([0-9A-Fa-f]+)>\s*<([0-9A-Fa-f]+)>', blk):
            table[int(src, 16)] = _u(dst)
    for blk in re.findall(rb'beginbfrange(.*?)endbfrange', text, re.S):
        for a, z, arr, dst in re.findall(
                rb'<([0-9A-Fa-f]+)>\s*<([0-9A-Fa-f]+)>\s*(?:\[([^\]]*)\]|<([0-9A-Fa-f]+)>)', blk):
            lo, hi = int(a, 16), int(z, 16)
            if arr:
                for k, h in enumerate(re.findall(rb'<([0-9A-Fa-f]+)>', arr)):
                    table[lo + k] = _u(h)
            else:
                base = int(dst, 16)
                for k in range(lo, hi + 1):
                    table[k] = chr(base + k - lo)
    return table


def pdf_text(path) -> str:
    """All text drawn in the PDF at ``path``, in stream order."""
    b = open(path, 'rb').read()
    objs = _objects(b)
    fonts = {}
    for name, num in set(re.findall(rb'/(F\d+) (\d+) 0 R', b)):
        o = b[objs[int(num)]:objs[int(num)] + 400]
        m = re.search(rb'/ToUnicode (\d+) 0 R', o)
        if m:
            fonts[name] = _cmap(_stream(b, objs[int(m.group(1))])[1])
    out = []
    for pos in objs.values():
        dict_end = b.find(b'>>', pos)
        if b'stream' not in b[dict_end:dict_end + 12]:
            continue
        try:
            head, data = _stream(b, pos)
        except Exception:
            continue
        if b'/Subtype' in head or b'Tj' not in data:
            continue
        font = {}
        for tok in re.finditer(rb'/(F\d+) [\d.]+ Tf|<([0-9A-Fa-f]+)> Tj', data):
            if tok.group(1):
                font = fonts.get(tok.group(1), {})
            else:
                h = tok.group(2)
                out.append(''.join(font.get(int(h[i:i + 4], 16), '?')
                                   for i in range(0, len(h), 4)))
    return ''.join(out)

