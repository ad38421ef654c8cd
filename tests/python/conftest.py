"""Shared helpers of the Python tests (run by ctest: tests/CMakeLists.txt
sets PYTHONPATH to build/python and ESTLAB_BINARY to the estlab command)."""
import csv
import json
import os
import subprocess

import numpy as np
import pytest

ESTLAB = os.environ.get('ESTLAB_BINARY', 'estlab')
SOURCE = os.environ.get('ESTLAB_SOURCE_DIR',
                        os.path.dirname(os.path.dirname(os.path.dirname(__file__))))


class Cli:
    """The estlab command in one folder."""

    def __init__(self, folder):
        self.folder = str(folder)

    def __call__(self, *args, expect=0):
        r = subprocess.run([ESTLAB] + [str(a) for a in args], cwd=self.folder,
                           capture_output=True, text=True)
        if expect is not None:
            assert r.returncode == expect, (args, r.returncode, r.stderr)
        return r

    def path(self, name):
        return os.path.join(self.folder, name)

    def read_csv(self, name):
        """name -> {column: float64 array}, empty cells NaN (as estlab reads them)."""
        with open(self.path(name), newline='') as f:
            rows = [r for r in csv.reader(f) if r and not r[0].startswith('#')]
        return {c: np.array([float(r[j]) if r[j] != '' else np.nan for r in rows[1:]])
                for j, c in enumerate(rows[0])}

    def write_csv(self, name, columns):
        names = list(columns)
        with open(self.path(name), 'w', newline='') as f:
            f.write(','.join(names) + '\n')
            for i in range(len(columns[names[0]])):
                f.write(','.join('' if np.isnan(columns[c][i]) else repr(float(columns[c][i]))
                                 for c in names) + '\n')

    def json(self, *args):
        return json.loads(self(*args).stdout)


@pytest.fixture
def cli(tmp_path):
    return Cli(tmp_path)


def same_columns(a, b, skip=()):
    """Every column of a is in b, bit for bit (NaN where NaN)."""
    assert list(a) == list(b), (list(a), list(b))
    for c in a:
        if c in skip:
            continue
        x, y = np.asarray(a[c]), np.asarray(b[c])
        assert x.shape == y.shape, c
        nan = np.isnan(x)
        assert np.array_equal(nan, np.isnan(y)), c
        assert np.array_equal(x[~nan].view(np.int64), y[~nan].view(np.int64)), c


_TIMINGS = ('wall_s', 'loop_s', 'us_per_step', 'read_s', 'write_s', 'iteration_wall_s')


def same_json(a, b, skip=_TIMINGS + ('out', 'files'),
              names=(('d.csv', 'data'),)):
    """The same JSON values, but for timings; the command line's file names
    (names: (file, the Python call's table)) read as the tables'."""
    if isinstance(a, dict):
        assert set(a) == set(b), (sorted(a), sorted(b))
        for k in a:
            if k not in skip:
                same_json(a[k], b[k], skip, names)
    elif isinstance(a, list):
        assert len(a) == len(b)
        for x, y in zip(a, b):
            same_json(x, y, skip, names)
    elif isinstance(a, str):
        for file, table in names:
            a = a.replace(file, table)
        assert a == b, (a, b)
    elif isinstance(a, float) and isinstance(b, float) and np.isnan(a):
        assert np.isnan(b)
    else:
        assert a == b, (a, b)
