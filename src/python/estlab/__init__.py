"""estlab from Python: the same filters, smoothers, simulations, tuner and
studies as the ``estlab`` command, on numpy arrays.

Every call runs the command's own core (the C++ of ``estlab filter``,
``estlab simulate``, ``estlab tune`` and ``estlab study``): the same keys,
the same checks and messages, the same numbers. Keyword arguments are the
command line's keys with ``_`` for ``-`` (``q_diag`` is ``--q-diag``);
values are numbers, sequences or arrays (written ``a,b,c``; a 2-D array
``a,b;c,d``), strings (as on the command line) or ``True`` for a flag. A
mapping is ``NAME=VALUE`` items: ``x0={'theta': 0.1}``,
``r_diag={'imu': [1e-2, 2.5e-3], 'gps': 0.25}``.

Example::

    import estlab
    sim = estlab.simulate('pendulum', t_end=5, dt=0.0125, x0={'theta': 0.785398},
                          params={'g': 9.8}, measure='sin', meas_noise=0.09, seed=1)
    run = estlab.filter('pendulum', sim, kind='ukf', params={'g': 9.8}, measure='sin',
                        integrator='euler', x0={'theta': 0.785398}, p0_diag=[0.1, 0.1],
                        q_white_accel=1, r_diag=0.09)
    run.x          # estimates, rows x states
    run.summary    # what 'estlab filter --json' prints

Errors: bad input raises ``estlab.InputError`` (the command line's exit 2)
with the command line's message; a numerical failure raises
``estlab.NumericalError`` (exit 1) whose ``result`` holds what was computed
before it. See docs/python.md.
"""

import collections.abc as _abc
import csv as _csv
import difflib as _difflib
import json as _json
import os as _os
import sys as _sys

import numpy as _np

# Model libraries compiled at run time resolve estlab's functions against
# this module: load it with its symbols global.
_flags = _sys.getdlopenflags()
_sys.setdlopenflags(_flags | _os.RTLD_GLOBAL)
try:
    from . import _estlab
finally:
    _sys.setdlopenflags(_flags)

InputError = _estlab.InputError
NumericalError = _estlab.NumericalError
__version__ = _estlab.version

__all__ = ['InputError', 'NumericalError', 'Model', 'models', 'simulate', 'filter', 'smooth',
           'tune', 'study', 'merge', 'figures', 'Simulation', 'FilterResult', 'TuneResult', 'StudyResult']

# Keys of the command line that have no meaning here: the results are
# returned, not written or printed.
_NOT_HERE = {
    'filter': {'help', 'json', 'out', 'plot', 'data'},
    'smooth': {'help', 'json', 'out', 'plot', 'data'},
    'simulate': {'help', 'json', 'out', 'data'},
    'tune': {'help', 'json', 'data', 'validate'},
}
# Python names beside the command line's (name -> key).
_ALIASES = {
    'filter': {'kind': 'filter', 'params': 'param'},
    'smooth': {'kind': 'filter', 'params': 'param'},
    'simulate': {'params': 'param', 'process_noise': 'process-noise-var',
                 'meas_noise': 'meas-noise-var'},
    'tune': {'kind': 'filter', 'params': 'param'},
}
_option_cache = {}


def _options(command):
    if command not in _option_cache:
        _option_cache[command] = dict(_estlab.options(command))
    return _option_cache[command]


# A value as the command line writes it (src/python/keywords.h).
_text = _estlab.text


def _key_error(command, name, options, aliases):
    names = sorted({k.replace('-', '_') for k in options if k not in _NOT_HERE[command]}
                   | set(aliases))
    close = _difflib.get_close_matches(name, names, n=1, cutoff=0.6)
    hint = " (did you mean '%s'?)" % close[0] if close else ''
    if name.replace('_', '-') in _NOT_HERE[command]:
        hint = (' (a command-line option: here the result is returned; data is the second '
                'argument)')
    return InputError("estlab.%s: unknown keyword '%s'%s" % (command, name, hint))


def _values(command, name, kind, value):
    """The texts the command line gives keyword `name` of kind `kind` for
    `value` (a flag: ['true'] when set, [] when not; src/python/keywords.h)."""
    return _estlab.values(command, name, kind, value)


def _args(command, kwargs):
    """The keyword arguments as the command line's arguments."""
    options = _options(command)
    aliases = _ALIASES.get(command, {})
    args = []
    for name, value in kwargs.items():
        if value is None:
            continue
        key = aliases.get(name, name.replace('_', '-'))
        kind = options.get(key)
        if kind is None or key in _NOT_HERE[command]:
            raise _key_error(command, name, options, aliases)
        for text in _values(command, name, kind, value):
            args += ['--' + key] if kind == 'flag' else ['--' + key, text]
    return args


def _numerical(message, result):
    """NumericalError with .result, and .step and .time where the message
    names them ("stopped at step 158 (t = 1.58, ...")."""
    import re
    e = NumericalError(message)
    e.result = result
    m = re.search(r'step (\d+) \(t = ([-+0-9.eE]+)', message)
    e.step = int(m.group(1)) if m else None
    e.time = float(m.group(2)) if m else None
    return e


def _model_arg(model):
    if type(model) is str and not model.endswith(('.model', '.h')):
        return model  # a built-in model's name
    if isinstance(model, Model):
        return model.spec
    if isinstance(model, (str, _os.PathLike)):
        return _model_spec(_os.fspath(model))
    raise InputError('model: a name (see estlab.models()), a path to a .model or .h file, or '
                     'an estlab.Model; got %r' % (model,))


def _model_spec(name):
    # A file is named by its absolute path, so that a later chdir keeps it.
    if (name.endswith('.model') or name.endswith('.h')) and _os.path.isfile(name):
        return _os.path.abspath(name)
    return name


def _columns(data, name):
    """data -> (column names, float64 columns, sidecar text)."""
    sidecar = ''
    if isinstance(data, Simulation):
        sidecar = data.sidecar
        data = data.columns
    if type(data) is dict or isinstance(data, _abc.Mapping):
        names = list(data.keys())
        values = [data[k] for k in names]
    elif hasattr(data, 'columns') and hasattr(data, '__getitem__'):  # a data frame
        names = [str(c) for c in data.columns]
        values = [data[c] for c in data.columns]
    elif getattr(getattr(data, 'dtype', None), 'names', None):  # a structured array
        names = list(data.dtype.names)
        values = [data[c] for c in names]
    else:
        raise InputError('%s: a mapping of column name to 1-D array (e.g. {"t": t, "z_x": z}), '
                         'got %s' % (name, type(data).__name__))
    columns = []
    for key, v in zip(names, values):
        if type(key) is not str:
            raise InputError('%s: column names must be strings, got %r' % (name, key))
        if (type(v) is _np.ndarray and v.dtype == _np.float64 and v.ndim == 1
                and v.flags.c_contiguous):
            columns.append(v)  # as it is: the C++ side copies it
            continue
        try:
            a = _np.asarray(v, dtype=float)
        except (TypeError, ValueError):
            raise InputError("%s: column '%s' is not numbers" % (name, key)) from None
        if a.ndim != 1:
            raise InputError("%s: column '%s' has shape %s; give 1-D arrays" % (name, key, a.shape))
        columns.append(_np.ascontiguousarray(a))
    return names, columns, sidecar


def _tables(data, name):
    """data (one table or a list of them) -> ({file name: table}, [file names])."""
    if isinstance(data, (list, tuple)):
        files = ['%s[%d]' % (name, i) for i in range(len(data))]
        return {f: _columns(d, f) for f, d in zip(files, data)}, files
    return {name: _columns(data, name)}, [name]


def _x0_keys(model, kwargs):
    """kwargs['x0'] given as one number per state (in the model's order) as
    the mapping NAME=VALUE the command line takes."""
    if 'x0' in kwargs:
        kwargs['x0'] = _x0_mapping(model, kwargs['x0'])


def _x0_mapping(model, x0):
    """x0 as a sequence of numbers: one per state, in the model's order."""
    if x0 is None or type(x0) is dict or isinstance(x0, (str, _abc.Mapping)):
        return x0
    states = Model(model).states if not isinstance(model, Model) else model.states
    try:
        values = _np.atleast_1d(_np.asarray(x0, dtype=float))
    except (TypeError, ValueError):
        raise InputError('x0: cannot use %r (a mapping, or one number per state)' % (x0,)) from None
    if values.shape != (len(states),):
        raise InputError('x0: %d values for the %d states %s (or give a mapping)'
                         % (values.size, len(states), ', '.join(states)))
    return dict(zip(states, values))


class Model:
    """A model: a built-in name, or a path to a .model or .h file (compiled on
    first use and cached, as the command line does).

    Attributes: name, description, states, params (name -> default),
    param_info (constraints, descriptions), inputs, units (state or input
    -> unit, '' when dimensionless), measurements (name -> outputs), groups
    (measurement -> {group: outputs}), stiff, discrete_time, invariants.
    """

    def __init__(self, name, _info=None):
        self.spec = _model_spec(_os.fspath(name)) if _info is None else name
        info = _info if _info is not None else _json.loads(_estlab.model_json(self.spec))
        self.info = info
        self.name = info['name']
        self.description = info.get('description', '')
        self.states = list(info['states'])
        self.param_info = list(info['params'])
        self.params = {p['name']: p['default'] for p in self.param_info}
        self.inputs = list(info.get('inputs', []))
        # state or input name -> its unit ('' = dimensionless)
        self.units = dict(zip(self.states, info.get('state_units', [])))
        self.units.update(zip(self.inputs, info.get('input_units', [])))
        self.measurements = {m['name']: list(m['outputs']) for m in info['measurements']}
        self.groups = {m['name']: dict(m['groups']) for m in info['measurements']
                       if m.get('groups')}
        self.stiff = info.get('stiff', False)
        self.discrete_time = info.get('discrete_time', False)
        self.invariants = list(info.get('invariants', []))

    def __repr__(self):
        return 'estlab.Model(%r: states %s)' % (self.name, ', '.join(self.states))


def models():
    """The built-in models (estlab list), as Model objects."""
    return _run_command('list', ['--json'], {}, lambda out, notes: [
        Model(m['name'], _info=m) for m in _json.loads(out)['models']])


class Simulation(_abc.Mapping):
    """What estlab.simulate returns: the columns (t, the states, the inputs,
    z_<output>) as 1-D arrays by name, and the settings (sidecar, what
    'estlab simulate' writes to OUT.json). Usable as data: estlab.filter then
    takes the states' columns as the truth, as the command line does with
    OUT.json.

    Attributes: columns, t, x (rows x states), z (rows x outputs or None),
    states, outputs, summary (what --json prints), settings (the sidecar as
    a dict).
    """

    def __init__(self, names, table, sidecar, summary_json):
        self.table = table
        self.columns = {c: table[:, i] for i, c in enumerate(names)}
        self.sidecar = sidecar
        self.settings = _json.loads(sidecar)
        self.summary = _json.loads(summary_json)
        self.states = list(self.settings['states'])
        self.outputs = list(self.settings.get('outputs') or [])

    def __getitem__(self, key):
        return self.columns[key]

    def __iter__(self):
        return iter(self.columns)

    def __len__(self):
        return len(self.columns)

    @property
    def t(self):
        return self.columns['t']

    @property
    def x(self):
        return _np.column_stack([self.columns[s] for s in self.states])

    @property
    def z(self):
        if not self.outputs:
            return None
        return _np.column_stack([self.columns['z_' + o] for o in self.outputs])

    def __repr__(self):
        return 'estlab.Simulation(%d rows: %s)' % (len(self.t), ', '.join(self.columns))


def simulate(model, t=None, u=None, **kwargs):
    """Integrate a model (estlab simulate): the rows at times t (an array;
    else t_end= and dt=), the input u (an array, rows x inputs for several;
    or a constant or signal string such as 'prbs(amplitude=2, period=0.2)'
    when t is not given), x0= (a mapping, or one value per state),
    params=, process_noise= (per-state variances), measure=,
    meas_noise= (per-output variances), sensor_rate=, seed=, integrator=,
    ... (every key of 'estlab simulate --help'). Returns a Simulation.
    """
    _x0_keys(model, kwargs)
    args = ['--model', _model_arg(model)]
    tables = {}
    if t is not None:
        record = {'t': _np.asarray(t, dtype=float)}
        if u is not None:
            if isinstance(u, str):
                raise InputError('u: a signal string applies with t_end= and dt=; with t, give '
                                 'the input values (one per time)')
            inputs = (model if isinstance(model, Model) else Model(model)).inputs
            ua = _np.asarray(u, dtype=float)
            ua = ua.reshape(len(ua), 1) if ua.ndim == 1 else ua
            if ua.ndim != 2 or ua.shape[1] != len(inputs):
                raise InputError('u: shape %s for the %d input(s) %s (rows x inputs)'
                                 % (ua.shape, len(inputs), ', '.join(inputs)))
            for j, name in enumerate(inputs):
                record[name] = ua[:, j]
        tables, _ = _tables(record, 'data')
        args += ['--data', 'data']
    elif u is not None:
        kwargs['input'] = u
    args += _args('simulate', kwargs)
    names, table, sidecar, summary, status, error = _estlab.simulate(args, tables)
    result = Simulation(names, table, sidecar, summary)
    if status != 0:
        raise _numerical(error, result)
    return result


class FilterResult:
    """What estlab.filter and estlab.smooth return.

    Attributes: columns (every column of 'estlab filter --out' by name), t,
    x (rows x states), P (rows x states x states: the covariances given,
    with full_cov=True, else the variances on the diagonal), nu and S (the
    innovations and their covariances; NaN where a component was missing),
    nis, loglik, err and nees (None without truth), summary (what --json
    prints), status, ok, table (rows x columns, in `names` order).
    Arrays are made when first asked for.
    """

    def __init__(self, run):
        self._run = run
        self._names = None
        self._cache = {}
        self._summary = None
        self._states = None

    @property
    def names(self):
        if self._names is None:
            self._names = self._run.columns
        return self._names

    @property
    def states(self):
        if self._states is None:
            self._states = [c[:-4] for c in self.names if c.endswith('_est')]
        return self._states

    def __getitem__(self, key):
        if key not in self._cache:
            self._cache[key] = self._run.column(key)
        return self._cache[key]

    def __contains__(self, key):
        return key in self.names

    def __len__(self):
        return self._run.rows

    @property
    def columns(self):
        return {c: self[c] for c in self.names}

    @property
    def table(self):
        return self._run.table()

    @property
    def summary(self):
        if self._summary is None:
            self._summary = _json.loads(self._run.summary_json())
        return self._summary

    @property
    def status(self):
        return self.summary['status']

    @property
    def ok(self):
        return 'message' not in self.summary

    @property
    def t(self):
        return self['t']

    def _stack(self, names):
        return self._run.stack(names) if names else None

    @property
    def x(self):
        return self._run.estimates()

    @property
    def P(self):
        n = len(self.states)
        P = _np.zeros((len(self), n, n))
        for i, a in enumerate(self.states):
            P[:, i, i] = self[a + '_var']
            for j, b in enumerate(self.states):
                c = 'cov_%s_%s' % (a, b)
                if c in self:
                    P[:, i, j] = P[:, j, i] = self[c]
        return P

    @property
    def outputs(self):
        return [c[3:] for c in self.names if c.startswith('nu_')]

    @property
    def nu(self):
        return self._stack(['nu_' + o for o in self.outputs])

    @property
    def S(self):
        outs = self.outputs
        if not outs:
            return None
        S = _np.zeros((len(self), len(outs), len(outs)))
        for i, a in enumerate(outs):
            S[:, i, i] = self['S_' + a]
            for j, b in enumerate(outs):
                c = 'S_%s_%s' % (a, b)
                if c in self:
                    S[:, i, j] = S[:, j, i] = self[c]
        return S

    def _optional(self, name):
        return self[name] if name in self else None

    @property
    def nis(self):
        return self._optional('nis')

    @property
    def loglik(self):
        return self._optional('loglik')

    @property
    def nees(self):
        return self._optional('nees')

    @property
    def err(self):
        names = [s + '_err' for s in self.states]
        return self._stack(names) if all(n in self for n in names) else None

    def __repr__(self):
        return 'estlab.FilterResult(%s, %d rows, status %s)' % (
            self.summary.get('smoother', self.summary.get('filter')), len(self), self.status)


def _filter(command, model, data, kwargs):
    _x0_keys(model, kwargs)
    names, columns, sidecar = _columns(data, 'data')
    run = _estlab.filter(command, _model_arg(model), names, columns, sidecar, kwargs,
                         _ALIASES[command])
    if run is None:  # a keyword for the command line's parser (config=, a misspelt key)
        args = ['--model', _model_arg(model), '--data', 'data'] + _args(command, kwargs)
        run = _estlab.filter_args(args, {'data': (names, columns, sidecar)}, command == 'smooth')
    result = FilterResult(run)
    if run.status != 0:
        raise _numerical(run.error, result)
    if run.warning:
        import warnings
        warnings.warn('estlab: ' + run.warning, RuntimeWarning, stacklevel=3)
    return result


def filter(model, data, **kwargs):
    """Run a filter over data (estlab filter): kind= (or filter=) 'kf',
    'ekf', 'iekf', 'ukf', 'ckf', 'ghkf', 'pf'; measure=, q_diag=, r_diag=,
    x0=, p0_diag=, params=, integrator=, truth= ([states] or not given:
    the states' columns of a Simulation), and every key of 'estlab filter
    --help'. data: a mapping of 1-D arrays (t, z_<output>, the inputs) or a
    Simulation. Returns a FilterResult.
    """
    return _filter('filter', model, data, kwargs)


def smooth(model, data, **kwargs):
    """Run a filter forward, then its smoother backward (estlab smooth): the
    keys of estlab.filter, and smoother_trajectories= for the particle
    smoother. Returns a FilterResult of the smoothed estimates (summary
    'filter': the forward filter's).
    """
    return _filter('smooth', model, data, kwargs)


class TuneResult:
    """What estlab.tune returns: summary (what 'estlab tune --json' prints,
    every number of the report), and from it q and r (the tuned matrices),
    params (estimated physical parameters), std_errors, x0, status,
    converged, starts (per-start results) and identifiability.
    """

    def __init__(self, summary_json, notes):
        self.summary = _json.loads(summary_json)
        self.notes = notes
        s = self.summary
        self.status = s.get('status')
        self.converged = s.get('status') == 'converged'
        self.q = _np.array(s['q_matrix']) if 'q_matrix' in s else None
        self.r = _np.array(s['r_matrix']) if 'r_matrix' in s else None
        tuned = s.get('tuned', {})
        self.params = dict(tuned.get('params', {}))
        self.x0 = tuned.get('x0')
        self.std_errors = dict(s.get('std_errors', {}))
        self.starts = s.get('starts', [])
        self.identifiability = s.get('identifiability')
        self.nll_initial = s.get('nll_initial')
        self.nll_tuned = s.get('nll_tuned')

    def __repr__(self):
        return 'estlab.TuneResult(status %s, NLL %s -> %s)' % (self.status, self.nll_initial,
                                                               self.nll_tuned)


def _notes(err):
    """The command's stderr less its progress lines; the error line apart."""
    notes, error = [], ''
    for line in err.replace('\r', '\n').splitlines():
        if line.startswith('estlab: error: '):
            error = line[len('estlab: error: '):]
        elif line.startswith('estlab: '):
            notes.append(line[len('estlab: '):])
    return notes, error


def _run_command(command, args, tables, make_result):
    """A whole command as the command line runs it (tune, study, merge,
    figures): its notes as warnings; exit 2 raises InputError, 130/143
    KeyboardInterrupt (a study stopped, resumable), any other failure
    NumericalError with .result; else make_result(stdout, notes)."""
    status, stdout, err = _estlab.run(command, args, tables)
    notes, error = _notes(err)
    if notes:
        import warnings
        for n in notes:
            warnings.warn('estlab: ' + n, RuntimeWarning, stacklevel=3)
    if status in (130, 143):
        raise KeyboardInterrupt('estlab %s: interrupted (call again to resume)' % command)
    if status == 2:
        raise InputError(error)
    result = make_result(stdout, notes)
    if status != 0:
        raise _numerical(error or '%s failed (exit %d)' % (command, status), result)
    return result


def tune(model, data, validate=None, **kwargs):
    """Tune Q and R, and physical parameters and initial states (estlab
    tune): estimator= 'ml' | 'em' | 'als' | 'output-error', kind=,
    measure=, estimate_param=[names], estimate_x0=[names], init_q_diag=,
    init_r_diag=, starts=, out= (a tuned.ini, written as the command line
    does), and every key of 'estlab tune --help'. data: one table or a
    list of them; validate= likewise. Returns a TuneResult; a fit that is
    not verified converged raises NumericalError with .result.
    """
    _x0_keys(model, kwargs)
    tables, files = _tables(data, 'data')
    args = ['--model', _model_arg(model)]
    for f in files:
        args += ['--data', f]
    if validate is not None:
        vtables, vfiles = _tables(validate, 'validate')
        tables.update(vtables)
        for f in vfiles:
            args += ['--validate', f]
    args += _args('tune', kwargs) + ['--json']
    return _run_command('tune', args, tables,
                        lambda out, notes: TuneResult(out, notes) if out.strip() else None)


class StudyResult:
    """What estlab.study returns: path (the results folder), summary (its
    summary.csv as columns: arrays of numbers, or of strings), report (the
    path of report.md), files (the folder's files) and info (what
    'estlab study --json' prints).
    """

    def __init__(self, path, info):
        self.path = path
        self.info = info
        self.report = _os.path.join(path, 'report.md')
        self.files = sorted(_os.listdir(path))
        self.summary = _read_csv_columns(_os.path.join(path, 'summary.csv'))

    def __repr__(self):
        return 'estlab.StudyResult(%r)' % self.path


def _read_csv_columns(path):
    if not _os.path.exists(path):
        return {}
    with open(path, newline='') as f:
        rows = list(_csv.reader(f))
    if not rows:
        return {}
    out = {}
    for j, name in enumerate(rows[0]):
        cells = [r[j] if j < len(r) else '' for r in rows[1:]]
        try:
            out[name] = _np.array([float(c) if c != '' else _np.nan for c in cells])
        except ValueError:
            out[name] = _np.array(cells, dtype=object)
    return out


def study(config, out, jobs=None, runs=None, shard=None, force=False):
    """Run a Monte Carlo study (estlab study CONFIG --out OUT): resumable,
    the same bytes for any jobs=. Ctrl-C stops it at the next run boundary
    (KeyboardInterrupt; call again to resume). Returns a StudyResult.
    """
    args = [_os.fspath(config), '--out', _os.fspath(out), '--json', '--quiet']
    for key, value in (('jobs', jobs), ('runs', runs), ('shard', shard)):
        if value is not None:
            args += ['--' + key, _text(value)]
    if force:
        args.append('--force')
    folder = _os.fspath(out)
    return _run_command('study', args, {}, lambda stdout, notes: StudyResult(
        folder, _json.loads(stdout) if stdout.strip() else {}) if _os.path.isdir(folder) else None)


def merge(out, shards):
    """Join the folders of sharded studies (study(..., shard='k/N')) into out
    (estlab merge OUT SHARD...): the same bytes as one unsharded run.
    Returns a StudyResult of out.
    """
    folder = _os.fspath(out)
    return _run_command('merge', [folder] + [_os.fspath(s) for s in shards], {},
                        lambda stdout, notes: StudyResult(folder, {})
                        if _os.path.isdir(folder) else None)


def figures(path):
    """Draw a finished study's figures with gnuplot (estlab figures DIR):
    PNG + SVG with their gnuplot scripts in path/figures. Returns the paths
    of the files written.
    """
    folder = _os.path.join(_os.fspath(path), 'figures')
    return _run_command('figures', [_os.fspath(path)], {}, lambda stdout, notes: sorted(
        _os.path.join(folder, f) for f in _os.listdir(folder)) if _os.path.isdir(folder) else [])
