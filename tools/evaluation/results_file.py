"""The evaluations' results as a JSON file, in one format for all of them."""
import json


def write_json(path, results, announce=True):
    """Write `results` to `path` (indented, keys sorted, numpy numbers as floats); say so on
    stdout when `announce`."""
    with open(path, 'w') as f:
        json.dump(results, f, indent=1, sort_keys=True, default=float)
    if announce:
        print('wrote %s' % path)
