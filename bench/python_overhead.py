"""The Python module's overhead (issue 36, done-when 2): one estlab.filter
call against the same work in C++, in one process, interleaved rounds.

  PYTHONPATH=build/python python3 bench/python_overhead.py [ROUNDS]

For each data size (10 steps, 400 000 steps) it prints the median over the
rounds of:
  run       the filter run alone: model.run_filter on a spec and data built
            once (what the benchmarks' RunFilter rows time);
  C++ API   the C++ call the module makes, from C++: the key table's
            settings and the columns in, the table made and checked, the spec
            built, the data loaded, the run (FilterRequest, ComputeFilter);
  args      the same from command-line arguments (program_options);
  Python    estlab.filter(...).x: keyword arguments to settings, numpy to
            the table, that C++ call, the estimates as an array.
"""
import statistics
import sys
import time

import numpy as np

import estlab

ROUNDS = int(sys.argv[1]) if len(sys.argv) > 1 else 7
MODEL = 'pendulum'
KEYS = [('measure', 'sin'), ('filter', 'ukf'), ('integrator', 'euler'), ('x0', 'theta=0.5'),
        ('p0-diag', '0.1,0.1'), ('q-diag', '1e-06,0.0001'), ('r-diag', '0.01')]
KWARGS = dict(measure='sin', kind='ukf', integrator='euler', x0={'theta': 0.5},
              p0_diag=[0.1, 0.1], q_diag=[1e-6, 1e-4], r_diag=0.01)


def data(steps):
    t = np.arange(steps) * 0.0125
    return {'t': t, 'z_sin_theta': np.sin(0.5 * np.cos(3.13 * t))}


def main():
    print('# estlab %s, %d interleaved rounds, median per call' % (estlab.__version__, ROUNDS))
    print('%-8s %11s %11s %11s %11s %14s %11s' % ('steps', 'run', 'C++ API', 'args',
                                                  'Python', 'Python - API', 'Python/API'))
    for steps, reps in ((10, 20000), (400000, 1)):
        d = data(steps)
        names, columns, _ = estlab._columns(d, 'data')
        tables = {'data': (names, columns, '')}
        args = ['--model', MODEL, '--data', 'data'] + estlab._args('filter', KWARGS)
        run, api, core, py = [], [], [], []
        for _ in range(ROUNDS):
            r, a, c = estlab._estlab.bench_filter(MODEL, KEYS, args, tables, reps)
            run.append(r)
            api.append(a)
            core.append(c)
            t0 = time.perf_counter()
            for _ in range(reps):
                estlab.filter(MODEL, d, **KWARGS).x  # the arrays a user reads
            py.append((time.perf_counter() - t0) / reps)
        r, a, c, p = (statistics.median(v) for v in (run, api, core, py))
        unit, scale = ('us', 1e6) if steps < 1000 else ('ms', 1e3)
        print('%-8d %8.2f %s %8.2f %s %8.2f %s %8.2f %s %11.2f %s %11.3f' % (
            steps, r * scale, unit, a * scale, unit, c * scale, unit, p * scale, unit,
            (p - a) * scale, unit, p / a))


if __name__ == '__main__':
    main()
