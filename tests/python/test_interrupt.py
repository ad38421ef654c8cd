"""Ctrl-C during a long call raises KeyboardInterrupt soon, and leaves the
module usable (issue 36: long calls can be interrupted): a particle filter
over a long record, a tuning, a study (which stops at a run boundary)."""
import os
import signal
import threading
import time

import numpy as np
import pytest

import estlab
from conftest import SOURCE

T = np.arange(400000) * 0.0125
DATA = {'t': T, 'z_sin_theta': np.sin(0.5 * np.cos(3.13 * T))}
KW = dict(measure='sin', integrator='euler', x0={'theta': 0.5}, p0_diag=[0.1, 0.1])


def run(seconds, call):
    timer = threading.Timer(seconds, os.kill, (os.getpid(), signal.SIGINT))
    start = time.monotonic()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        call()
    timer.join()
    return time.monotonic() - start - seconds


def test_a_long_particle_filter_stops():
    # 400 000 steps of 3000 particles: minutes, were it not stopped.
    late = run(0.5, lambda: estlab.filter('pendulum', DATA, kind='pf', particles=3000,
                                          q_diag=[1e-6, 1e-4], r_diag=0.01, **KW))
    assert late < 5, late
    assert estlab.filter('pendulum', {k: v[:50] for k, v in DATA.items()}, kind='ukf',
                         q_diag=[1e-6, 1e-4], r_diag=0.01, **KW).ok


def test_a_long_tuning_stops():
    late = run(0.5, lambda: estlab.tune('pendulum', DATA, kind='ukf', init_q_diag=[1e-6, 1e-4],
                                        init_r_diag=0.01, starts=8, **KW))
    assert late < 10, late


def test_a_study_stops_and_resumes(tmp_path):
    config = os.path.join(SOURCE, 'tests', 'python', 'data', 'tiny_study.ini')
    out = str(tmp_path / 'study')
    run(0.3, lambda: estlab.study(config, out=out, runs=400, jobs=1))
    done = estlab.study(config, out=out, runs=400, jobs=1)  # resumes
    assert len(done.summary) > 0
