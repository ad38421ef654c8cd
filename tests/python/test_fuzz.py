"""Random keyword arguments never crash the interpreter: every call returns
or raises estlab.InputError / estlab.NumericalError (issue 36, done-when 3)."""
import random

import numpy as np

import estlab

VALUES = [0, 1, -1, 2.5, 1e308, -1e-320, float('nan'), float('inf'), '', ' ', 'x', 'ekf',
          'a=1', 'theta=', '=1', '1,2,3', ';;', 'prbs(', '\x00', '\u00e9', 'nan', '-0',
          [], [1], [1, 2], [[1, 2], [3, 4]], [[1], [2, 3]], {'theta': 1}, {'': 2},
          {'position': [1, 2]}, True, False, None, np.zeros((2, 2, 2)), (1, 'a'), 10**30,
          object(), b'bytes', 'file(/dev/zero)', '../../etc/passwd']


def keys(command):
    # model, data and validate are the calls' own arguments
    return [k.replace('-', '_') for k, _ in estlab._estlab.options(command)
            if k not in ('model', 'data', 'validate')] + ['kind', 'params', 'q_dag', 'zzz', '']


def call(fn, *args, **kw):
    """'ok', 'InputError' or 'NumericalError' (anything else fails the test)."""
    try:
        fn(*args, **kw)
        return 'ok'
    except estlab.InputError:
        return 'InputError'
    except estlab.NumericalError:
        return 'NumericalError'



FILTER = dict(measure='sin', r_diag=0.1, q_diag=[1e-4, 1e-4], x0={'theta': 0.5})
SIMULATE = dict(t_end=0.2, measure='sin', meas_noise=0.01)
TUNE = dict(measure='sin', init_r_diag=0.1, init_q_diag=[1e-4, 1e-4], max_iterations=3)


def fuzzed(rng, base, names):
    """base with 1 to 3 keys set to random values (a valid call otherwise)."""
    kw = dict(base)
    for _ in range(rng.randint(1, 3)):
        kw[rng.choice(names)] = rng.choice(VALUES)
    kw.pop('', None)
    return kw


def test_random_keywords_never_crash():
    rng = random.Random(36)
    t = np.arange(30) * 0.01
    data = {'t': t, 'z_sin_theta': np.sin(t)}
    filter_keys, sim_keys, tune_keys = keys('filter'), keys('simulate'), keys('tune')
    outcomes = {'ok': 0, 'InputError': 0, 'NumericalError': 0}
    for i in range(400):
        outcomes[call(estlab.filter, 'pendulum', data, **fuzzed(rng, FILTER, filter_keys))] += 1
        outcomes[call(estlab.smooth, 'pendulum', data, **fuzzed(rng, FILTER, filter_keys))] += 1
        outcomes[call(estlab.simulate, 'pendulum', **fuzzed(rng, SIMULATE, sim_keys))] += 1
        if i % 10 == 0:
            outcomes[call(estlab.tune, 'pendulum', data, **fuzzed(rng, TUNE, tune_keys))] += 1
    # Both kinds of outcome occur: the fuzz reaches the runs, not only the checks.
    assert outcomes['ok'] > 20 and outcomes['InputError'] > 100, outcomes
    # The interpreter is still whole: a good call after the fuzz works.
    run = estlab.filter('pendulum', data, **FILTER)
    assert run.x.shape == (30, 2)
