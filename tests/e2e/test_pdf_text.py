"""The tests' PDF text reader keeps a content stream whose compressed bytes end
in a line feed (the end-of-line before ``endstream`` is not data, but a byte of
the compressed stream may be the same character)."""

import zlib

from .pdf_text import pdf_text


def _pdf_with(content: bytes) -> bytes:
    z = zlib.compress(content)
    cmap = b"beginbfchar\n<0041> <0041>\n<0042> <0042>\nendbfchar"
    font = b"1 0 obj\n<< /Type /Font /ToUnicode 2 0 R >>\nendobj\n"
    tounicode = b"2 0 obj\n<< /Length " + str(len(cmap)).encode() + b" >>\nstream\n"
    page = (b"3 0 obj\n<< /Length " + str(len(z)).encode() + b" /Filter /FlateDecode >>"
            b"\nstream\n")
    return (b"%PDF-1.4\n" + font + tounicode + cmap + b"\nendstream\nendobj\n"
            + page + z + b"\nendstream\nendobj\n/F1 1 0 R\n")


def test_a_compressed_stream_ending_in_a_line_feed_is_read(tmp_path):
    # find a page text whose compressed form ends in LF (the adler32's last byte)
    for k in range(4096):
        content = b"/F1 12 Tf <00410042> Tj % " + str(k).encode()
        if zlib.compress(content).endswith(b"\n"):
            break
    else:  # pragma: no cover - 1 in 256 texts ends so; 4096 tries always find one
        raise AssertionError("no text found whose compressed form ends in LF")
    p = tmp_path / "t.pdf"
    p.write_bytes(_pdf_with(content))
    assert pdf_text(p) == "AB"
