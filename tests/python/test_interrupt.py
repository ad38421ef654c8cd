"""Ctrl-C during a long call raises KeyboardInterrupt soon, and leaves the
module usable (issue 36: long calls can be interrupted): a particle filter
over a long record, a tuning, a study (which stops at a run boundary)."""
import os
import subprocess
import sys
import signal
import threading
import time

import numpy as np
import pytest

import estlab
from conftest import ESTLAB, SOURCE

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


def ctrl_c_during_the_first_compile(tmp_path, argv):
    """Runs argv in a session of its own on a model file never compiled
    before (its own cache folder), presses Ctrl-C for the whole session (as
    a terminal does: the compiler gets it too) once the compile has begun;
    returns (exit status, stdout, stderr)."""
    model = tmp_path / 'tanks.model'
    with open(os.path.join(SOURCE, 'examples', 'two_tanks', 'two_tanks.model')) as f:
        model.write_text(f.read() + '\n# %s\n' % tmp_path)
    env = dict(os.environ, XDG_CACHE_HOME=str(tmp_path / 'cache'))
    p = subprocess.Popen([a.replace('MODEL', str(model)) for a in argv], env=env,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         start_new_session=True)
    first = p.stderr.readline()
    assert 'compiling model' in first, first
    time.sleep(0.5)
    os.killpg(p.pid, signal.SIGINT)
    out, err = p.communicate(timeout=60)
    return p.returncode, out, first + err


def test_ctrl_c_during_a_first_compile_is_an_interrupt_not_a_compile_error(tmp_path):
    code = ('import estlab\ntry:\n    estlab.Model("MODEL")\n'
            'except KeyboardInterrupt:\n    print("KeyboardInterrupt")\n')
    status, out, err = ctrl_c_during_the_first_compile(tmp_path, [sys.executable, '-c', code])
    assert out.strip() == 'KeyboardInterrupt' and 'does not compile' not in err, (out, err)
    assert status == 0
    status, out, err = ctrl_c_during_the_first_compile(
        tmp_path, [ESTLAB, 'list', '--model', 'MODEL'])
    assert status == -signal.SIGINT and 'does not compile' not in err, (status, err)
