"""The Python calls and the command line on the same inputs give the same
numbers, bit for bit (issue 36, done-when 1): simulate, filter and smooth
(every filter kind, missing components), tune, study and the model list."""
import json
import os
import shutil

import numpy as np
import pytest

import estlab
from conftest import SOURCE, same_columns, same_json

PENDULUM = dict(params={'g': 9.8}, x0={'theta': 0.785398})
SIM_ARGS = ['simulate', '--model', 'pendulum', '--param', 'g=9.8', '--x0', 'theta=0.785398',
            '--t-end', '2', '--dt', '0.0125', '--measure', 'sin', '--meas-noise-var', '0.09',
            '--process-noise-var', '1e-6,1e-4', '--seed', '3']


def simulate_both(cli):
    cli(*SIM_ARGS, '--out', 'd.csv')
    sim = estlab.simulate('pendulum', t_end=2, dt=0.0125, measure='sin', meas_noise=0.09,
                          process_noise=[1e-6, 1e-4], seed=3, **PENDULUM)
    return sim


def test_simulate_matches_the_command_line(cli):
    sim = simulate_both(cli)
    same_columns(cli.read_csv('d.csv'), sim.columns)
    with open(cli.path('d.csv.json')) as f:
        sidecar = json.load(f)
    same_json(sidecar, sim.settings)
    assert sim.x.shape == (161, 2) and sim.z.shape == (161, 1)


def test_simulate_with_recorded_input_matches_the_command_line(cli):
    t = np.linspace(0.0, 1.0, 41) ** 1.5  # rows off any grid
    u = np.sin(7 * t)
    cli.write_csv('u.csv', {'t': t, 'u': u})
    cli('simulate', '--model', 'cart-pole', '--data', 'u.csv', '--x0', 'theta=0.1',
        '--integrator', 'rk4', '--measure', 'x-theta', '--meas-noise-var', '1e-4,1e-4',
        '--out', 'c.csv')
    sim = estlab.simulate('cart-pole', t=t, u=u, x0=[0, 0, 0.1, 0], integrator='rk4',
                          measure='x-theta', meas_noise=[1e-4, 1e-4])
    same_columns(cli.read_csv('c.csv'), sim.columns)


FILTER = ['--model', 'pendulum', '--param', 'g=9.8', '--measure', 'sin', '--integrator', 'euler',
          '--x0', 'theta=0.785398', '--p0-diag', '0.1,0.1', '--q-white-accel', '1',
          '--r-diag', '0.09']
FILTER_KW = dict(measure='sin', integrator='euler', p0_diag=[0.1, 0.1], q_white_accel=1,
                 r_diag=0.09, **PENDULUM)


@pytest.mark.parametrize('kind', ['ekf', 'iekf', 'ukf', 'ckf', 'ghkf', 'pf'])
def test_filter_matches_the_command_line(cli, kind):
    sim = simulate_both(cli)
    extra = ['--particles', '300', '--seed', '4'] if kind == 'pf' else []
    summary = cli.json('filter', *FILTER, '--filter', kind, '--data', 'd.csv', '--out', 'e.csv',
                       '--json', *extra)
    kw = dict(particles=300, seed=4) if kind == 'pf' else {}
    run = estlab.filter('pendulum', sim, kind=kind, **FILTER_KW, **kw)
    same_columns(cli.read_csv('e.csv'), run.columns)
    same_json(summary, run.summary)
    assert run.x.shape == (161, 2) and run.P.shape == (161, 2, 2) and run.nees is not None


def test_filter_with_missing_components_and_full_covariances(cli):
    sim = simulate_both(cli)
    data = {k: np.array(v) for k, v in sim.columns.items()}
    data['z_sin_theta'][::3] = np.nan  # every third sample missing
    cli.write_csv('m.csv', data)
    summary = cli.json('filter', *FILTER, '--filter', 'ukf', '--data', 'm.csv', '--out', 'e.csv',
                       '--json', '--full-cov', '--truth', 'theta,omega')
    run = estlab.filter('pendulum', data, kind='ukf', full_cov=True, truth='theta,omega',
                        **FILTER_KW)
    same_columns(cli.read_csv('e.csv'), run.columns)
    same_json(summary, run.summary, names=(('m.csv', 'data'),))
    assert np.isnan(run.nu[::3]).all() and not np.isnan(run.nu[1::3]).any()


@pytest.mark.parametrize('kind,extra', [('ukf', []), ('pf', ['--particles', '200'])])
def test_smooth_matches_the_command_line(cli, kind, extra):
    sim = simulate_both(cli)
    summary = cli.json('smooth', *FILTER, '--filter', kind, '--data', 'd.csv', '--out', 's.csv',
                       '--json', *extra)
    kw = dict(particles=200) if kind == 'pf' else {}
    run = estlab.smooth('pendulum', sim, kind=kind, **FILTER_KW, **kw)
    same_columns(cli.read_csv('s.csv'), run.columns)
    same_json(summary, run.summary)


def test_tune_matches_the_command_line(cli):
    sim = simulate_both(cli)
    args = ['--model', 'pendulum', '--param', 'g=9.8', '--measure', 'sin', '--filter', 'ukf',
            '--integrator', 'euler', '--x0', 'theta=0.785398', '--p0-diag', '0.1,0.1',
            '--init-q-diag', '1e-5,1e-3', '--init-r-diag', '0.5', '--estimate-param', 'g',
            '--out', 'tuned.ini']
    summary = cli.json('tune', *args, '--data', 'd.csv', '--json')
    tuned = estlab.tune('pendulum', sim, kind='ukf', measure='sin', integrator='euler',
                        p0_diag=[0.1, 0.1], init_q_diag=[1e-5, 1e-3], init_r_diag=0.5,
                        estimate_param=['g'], out=cli.path('py_tuned.ini'), **PENDULUM)
    same_json(summary, tuned.summary)
    assert tuned.converged and tuned.q.shape == (2, 2) and tuned.r.shape == (1, 1)
    assert abs(tuned.params['g'] - 9.8) < 5 * tuned.std_errors['g']
    lines = lambda p: [l for l in open(cli.path(p)) if not l.startswith('#')]
    assert lines('tuned.ini') == lines('py_tuned.ini')


def test_study_writes_the_same_files(cli, tmp_path):
    config = os.path.join(SOURCE, 'tests', 'python', 'data', 'tiny_study.ini')
    cli('study', config, '--out', 'cli_out', '--runs', '3', '--jobs', '1', '--quiet')
    result = estlab.study(config, out=str(tmp_path / 'py_out'), runs=3, jobs=2)
    for name in ('runs.csv', 'summary.csv'):
        with open(cli.path('cli_out/' + name), 'rb') as a, open(result.path + '/' + name,
                                                                 'rb') as b:
            assert a.read() == b.read(), name
    assert len(result.summary) > 0 and os.path.exists(result.report)


def test_models_are_the_command_lines(cli):
    listed = cli.json('list', '--json')
    assert [m.name for m in estlab.models()] == [m['name'] for m in listed['models']]
    m = estlab.Model('cart-pole')
    assert m.states == ['x', 'v', 'theta', 'omega'] and m.inputs == ['u']
    assert m.groups['x-theta'] == {'position': ['x'], 'encoder': ['theta']}
    assert m.units['theta'] == 'rad' and m.units['x'] == 'm' and 'u' in m.units, m.units


@pytest.mark.parametrize('estimator,extra', [
    ('em', ['--filter', 'ekf', '--max-iterations', '20']),
    ('als', ['--filter', 'ekf']),
    ('output-error', ['--estimate-param', 'g']),
    ('ml', ['--filter', 'ekf', '--estimate-x0', 'theta', '--starts', '3', '--jobs', '2']),
])
def test_every_estimator_matches_the_command_line(cli, estimator, extra):
    """The same JSON whether the fit converged (exit 0) or not (exit 1:
    NumericalError with the result)."""
    sim = simulate_both(cli)
    args = ['--model', 'pendulum', '--param', 'g=9.5', '--measure', 'sin', '--integrator',
            'euler', '--x0', 'theta=0.7', '--p0-diag', '0.1,0.1', '--init-q-diag', '1e-5,1e-3',
            '--init-r-diag', '0.5', '--estimator', estimator, *extra]
    r = cli('tune', *args, '--data', 'd.csv', '--json', expect=None)
    assert r.returncode in (0, 1), r.stderr
    kw = {}
    for key, value in zip(extra[::2], extra[1::2]):
        kw[key[2:].replace('-', '_')] = value
    try:
        tuned = estlab.tune('pendulum', sim, params={'g': 9.5}, measure='sin', integrator='euler',
                            x0={'theta': 0.7}, p0_diag=[0.1, 0.1], init_q_diag=[1e-5, 1e-3],
                            init_r_diag=0.5, estimator=estimator, **kw)
        assert r.returncode == 0, r.stderr
    except estlab.NumericalError as e:
        assert r.returncode == 1
        tuned = e.result
        assert str(e) in r.stderr
    same_json(json.loads(r.stdout), tuned.summary)


def test_shards_merge_and_figures_as_on_the_command_line(cli, tmp_path):
    config = os.path.join(SOURCE, 'tests', 'python', 'data', 'tiny_study.ini')
    cli('study', config, '--out', 'whole', '--runs', '4', '--quiet')
    shards = [str(tmp_path / ('s%d' % k)) for k in (1, 2)]
    for k, folder in enumerate(shards, 1):
        estlab.study(config, out=folder, runs=4, shard='%d/2' % k)
    merged = estlab.merge(tmp_path / 'merged', shards)
    for name in ('runs.csv', 'summary.csv', 'steps.csv'):
        with open(cli.path('whole/' + name), 'rb') as a, open(merged.path + '/' + name, 'rb') as b:
            assert a.read() == b.read(), name
    drawn = estlab.figures(merged.path)
    assert any(f.endswith('.png') for f in drawn) and any(f.endswith('.gp') for f in drawn)


def test_keyword_values_are_written_as_python_writes_them():
    """Every float keyword reaches the command's parser as repr() writes it:
    the shortest text that reads back to the same double."""
    rng = np.random.default_rng(5)
    xs = np.concatenate([rng.standard_normal(300) * 10.0 ** rng.integers(-320, 300, 300),
                         [0.0, -0.0, 5e-324, 1e16, 1e-5, 100000.0, 0.1, 1 / 3]])
    for x in xs.tolist():
        text = estlab._estlab.text(x)
        assert text == repr(x) and np.float64(text).view(np.int64) == np.float64(x).view(np.int64)
    assert estlab._estlab.text(list(xs[:5])) == ','.join(repr(x) for x in xs[:5].tolist())
    assert estlab._estlab.text(np.array([[1, 0.5], [0, 2]])) == '1.0,0.5;0.0,2.0'
    assert estlab._estlab.text({'theta': 0.5, 'n': np.int64(3)}) == 'theta=0.5,n=3'


def test_the_fast_path_and_the_command_lines_parser_give_the_same_run(cli):
    """estlab.filter's keywords go straight into the key table's settings;
    the same keywords as command-line arguments (the path a config= or a
    misspelt key takes) give the same numbers."""
    sim = simulate_both(cli)
    kw = dict(FILTER_KW, kind='ukf', full_cov=True, q_diag=np.array([1e-6, 1e-4]))
    kw.pop('q_white_accel')
    fast = estlab.filter('pendulum', sim, **kw)
    names, columns, sidecar = estlab._columns(sim, 'data')
    assert estlab._estlab.filter('filter', 'pendulum', names, columns, sidecar, dict(kw),
                                 estlab._ALIASES['filter']) is not None  # the fast path ran
    args = ['--model', 'pendulum', '--data', 'data'] + estlab._args('filter', dict(kw))
    slow = estlab.FilterResult(estlab._estlab.filter_args(
        args, {'data': (names, columns, sidecar)}, False))
    same_columns(fast.columns, slow.columns)
    same_json(fast.summary, slow.summary)
