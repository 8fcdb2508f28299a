"""Writes a wrk Lua script that requests, round-robin, every frame URL of a dataset's first 50
items on a running server.

    python3 scripts/lib/frame_paths.py BASE DATASET > frames.lua
"""
import json
import sys
import urllib.request

base, dataset = sys.argv[1], sys.argv[2]
with urllib.request.urlopen(f"{base}/api/v1/datasets/{dataset}/items?per_page=50") as r:
    listing = json.load(r)
urls = set()
for it in listing["items"]:
    with urllib.request.urlopen(base + it["url"]) as r:
        urls.update(img["url"] for img in json.load(r)["images"])
print("paths = {" + ", ".join(json.dumps(u) for u in sorted(urls)) + "}")
print("i = 0")
print('request = function() i = i % #paths + 1; return wrk.format("GET", paths[i]) end')
