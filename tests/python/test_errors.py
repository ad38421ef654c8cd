"""Bad input raises estlab.InputError with the command line's message, a
numerical failure estlab.NumericalError with the rows computed before it
(issue 36, done-when 3)."""
import numpy as np
import pytest

import estlab
from conftest import Cli

KW = dict(params={'g': 9.8}, measure='sin', integrator='euler', x0={'theta': 0.785398},
          p0_diag=[0.1, 0.1], q_white_accel=1, r_diag=0.09)
CLI_FILTER = ['filter', '--model', 'pendulum', '--param', 'g=9.8', '--measure', 'sin',
              '--integrator', 'euler', '--x0', 'theta=0.785398', '--p0-diag', '0.1,0.1',
              '--q-white-accel', '1']


def data(n=20):
    t = np.arange(n) * 0.0125
    return {'t': t, 'z_sin_theta': np.sin(0.7 * np.cos(3 * t))}


def cli_message(cli, table, *args):
    """What the command line says after 'estlab: error: ' on the same data,
    with its file name as the Python call names its table ('data')."""
    cli.write_csv('data', table)
    r = cli(*CLI_FILTER, '--data', 'data', *args, expect=2)
    assert r.stderr.startswith('estlab: error: '), r.stderr
    return r.stderr[len('estlab: error: '):].strip()


def python_message(table, **kw):
    with pytest.raises(estlab.InputError) as e:
        estlab.filter('pendulum', table, **{**KW, **kw})
    return str(e.value)


def test_a_time_that_goes_backwards_names_the_row(cli):
    d = data()
    d['t'][7] = d['t'][3]
    assert python_message(d) == cli_message(cli, d, '--r-diag', '0.09')
    assert 'data:9' in python_message(d)  # row 7 is line 9 of the same file


def test_nan_time_infinite_value_and_a_bad_value_have_the_command_lines_messages(cli):
    d = data()
    d['t'][4] = np.nan
    assert python_message(d) == cli_message(cli, d, '--r-diag', '0.09')
    d = data()
    d['z_sin_theta'][2] = np.inf
    assert python_message(d) == cli_message(cli, d, '--r-diag', '0.09')
    assert python_message(data(), r_diag=-1) == cli_message(cli, data(), '--r-diag', '-1')
    assert python_message(data(), kind='ukq') == cli_message(cli, data(), '--r-diag', '0.09',
                                                             '--filter', 'ukq')


def test_a_missing_column_names_it(cli):
    d = data()
    del d['z_sin_theta']
    d['z_sine'] = np.zeros(20)
    assert python_message(d) == cli_message(cli, d, '--r-diag', '0.09')


def test_a_misspelt_keyword_names_the_closest_key():
    with pytest.raises(estlab.InputError, match="unknown keyword 'q_dag'.*'q_diag'"):
        estlab.filter('pendulum', data(), q_dag=[1, 1], **KW)
    with pytest.raises(estlab.InputError, match="'estimate_parm'.*'estimate_param'"):
        estlab.tune('pendulum', data(), estimate_parm=['g'])
    with pytest.raises(estlab.InputError, match="'meas_nosie'.*'meas_noise'"):
        estlab.simulate('pendulum', t_end=1, meas_nosie=0.1)
    with pytest.raises(estlab.InputError, match="'out'.*command-line option"):
        estlab.filter('pendulum', data(), out='e.csv', **KW)


def test_wrong_shapes_and_types():
    with pytest.raises(estlab.InputError, match="column 'z_sin_theta' has shape"):
        estlab.filter('pendulum', {'t': np.arange(4.0), 'z_sin_theta': np.zeros((4, 2))}, **KW)
    with pytest.raises(estlab.InputError, match="column 'z_sin_theta' has 3 values"):
        estlab.filter('pendulum', {'t': np.arange(4.0), 'z_sin_theta': np.zeros(3)}, **KW)
    with pytest.raises(estlab.InputError, match='mapping of column name'):
        estlab.filter('pendulum', np.zeros((4, 2)), **KW)
    with pytest.raises(estlab.InputError, match="not numbers"):
        estlab.filter('pendulum', {'t': ['a', 'b'], 'z_sin_theta': [1, 2]}, **KW)
    with pytest.raises(estlab.InputError, match='x0: 3 values for the 2 states'):
        estlab.simulate('pendulum', t_end=1, x0=[1, 2, 3])
    with pytest.raises(estlab.InputError, match='flag'):
        estlab.filter('pendulum', data(), full_cov='yes', **KW)
    with pytest.raises(estlab.InputError, match="unknown model 'no-such-model'"):
        estlab.filter('no-such-model', data(), **KW)


def test_a_numerical_failure_keeps_the_rows_before_it(cli):
    cli('simulate', '--model', 'van-der-pol', '--x0', 'x=2', '--t-end', '2', '--dt', '0.01',
        '--measure', 'x', '--meas-noise-var', '0.01', '--out', 'v.csv')
    with pytest.raises(estlab.NumericalError) as e:
        estlab.filter('van-der-pol', cli.read_csv('v.csv'), kind='ekf', measure='x',
                      integrator='euler', x0={'x': 2}, q_diag=[1e-4, 1e-4], r_diag=0.01)
    assert 'step' in str(e.value) and 't = ' in str(e.value)
    assert 1 <= len(e.value.result.t) < 201 and not e.value.result.ok
    r = cli('filter', '--model', 'van-der-pol', '--measure', 'x', '--filter', 'ekf', '--data',
            'v.csv', '--integrator', 'euler', '--x0', 'x=2', '--q-diag', '1e-4,1e-4',
            '--r-diag', '0.01', expect=1)
    assert 'estlab: error: ' + str(e.value).replace('data line', 'v.csv line') in r.stderr
    assert e.value.step == 158 and e.value.time == 1.58
