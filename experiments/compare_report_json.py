"""Every number of one set of ``camjax program --format json`` reports within 1e-10 relative
of another's (a value that is null in the first may be a number in the second: an output
newly computed; a list empty in the first may be filled).

Write the two sets from two checkouts, e.g. for each built-in (indexer, feed, servo, valve)
and speeds (600, 200:1400:7, 100,350,900; the valve at 1000, 500:3000:6, 1000,2000):

    CAMJAX_CACHE_DIR=off PYTHONPATH=<checkout> python -m camjax program indexer --rpm 200:1400:7 \
        --format json > <dir>/indexer_200_1400_7.json

then ``python experiments/compare_report_json.py <before dir> <after dir>``.
"""

import json
import pathlib
import sys

a_dir, b_dir = map(pathlib.Path, sys.argv[1:3])
bad = 0
count = 0
filled = 0


def walk(a, b, path):
    global bad, count, filled
    if isinstance(a, dict):
        if not isinstance(b, dict):
            print(path, "type", type(b))
            bad += 1
            return
        for k in a:
            if k not in b:
                print(path + "/" + k, "missing")
                bad += 1
                continue
            walk(a[k], b[k], path + "/" + k)
    elif isinstance(a, list):
        if not isinstance(b, list) or len(a) != len(b):
            if a == []:
                filled += 1
                return
            print(path, "list", len(a), None if not isinstance(b, list) else len(b))
            bad += 1
            return
        for i, (x, y) in enumerate(zip(a, b)):
            walk(x, y, f"{path}[{i}]")
    elif isinstance(a, bool) or isinstance(a, str) or a is None:
        if a is None and b is not None:
            filled += 1
            return
        if a != b:
            print(path, a, b)
            bad += 1
    else:
        count += 1
        if (
            not isinstance(b, (int, float))
            or isinstance(b, bool)
            or abs(a - b) > 1e-10 * max(abs(a), 1e-300)
            and abs(a - b) > 0
        ):
            print(
                path,
                a,
                b,
                None if not isinstance(b, (int, float)) else abs(a - b) / max(abs(a), 1e-300),
            )
            bad += 1


for f in sorted(a_dir.glob("*.json")):
    a = json.loads(f.read_text())
    b = json.loads((b_dir / f.name).read_text())
    walk(a, b, f.name)
print(f"{count} numbers compared, {filled} nulls now filled, {bad} differences")
