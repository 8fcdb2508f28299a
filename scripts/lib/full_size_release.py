"""Writes a full-size ENACT release by replicating a small real one: copies of every item with
`_rN` ids until TARGET items, each copy's images written again with a `tEXt` chunk naming the
copy, so every image's bytes (and content hash) are distinct and nothing deduplicates at import.
The QA file keeps ENACT's format; the images keep their pixels.

    python3 scripts/lib/full_size_release.py SOURCE_RELEASE OUT_DIR TARGET

Prints the number of items, images and bytes written.
"""
import json
import os
import struct
import sys
import zlib

source, out, target = sys.argv[1], sys.argv[2], int(sys.argv[3])
qa = os.path.join(source, "QA", "enact_ordering.jsonl")
records = [json.loads(line) for line in open(qa, encoding="utf-8") if line.strip()]
if not records:
    sys.exit(f"{qa}: no items")


def with_text_chunk(png: bytes, text: str) -> bytes:
    """`png` with a tEXt chunk inserted before IEND (the last 12 bytes)."""
    if png[-12:-8] != b"\x00\x00\x00\x00" or png[-8:-4] != b"IEND":
        raise ValueError("not a PNG ending in IEND")
    data = b"Comment\x00" + text.encode("ascii")
    chunk = struct.pack(">I", len(data)) + b"tEXt" + data
    chunk += struct.pack(">I", zlib.crc32(b"tEXt" + data) & 0xFFFFFFFF)
    return png[:-12] + chunk + png[-12:]


originals = {}
os.makedirs(os.path.join(out, "QA"), exist_ok=True)
items = images = written = 0
with open(os.path.join(out, "QA", "enact_ordering.jsonl"), "w", encoding="utf-8") as qa_out:
    copy = 0
    while items < target:
        for record in records:
            if items >= target:
                break
            new = dict(record)
            new["id"] = f"{record['id']}_r{copy}"
            paths = []
            for path in record["images"]:
                if path not in originals:
                    with open(os.path.join(source, path), "rb") as f:
                        originals[path] = f.read()
                head, name = os.path.split(path)
                new_path = os.path.join(head, f"copy_{copy}", name)
                full = os.path.join(out, new_path)
                os.makedirs(os.path.dirname(full), exist_ok=True)
                data = with_text_chunk(originals[path], f"enact-hub copy {copy}")
                with open(full, "wb") as f:
                    f.write(data)
                paths.append(new_path)
                images += 1
                written += len(data)
            new["images"] = paths
            qa_out.write(json.dumps(new) + "\n")
            items += 1
        copy += 1
print(json.dumps({"items": items, "images": images, "bytes": written}))
