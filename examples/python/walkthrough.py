"""estlab from Python, as a notebook would use it: simulate a pendulum,
tune the filter's noise and the gravity from a guess, filter and smooth with
the tuned values, and plot (matplotlib).

Run from the build tree (docs/python.md):
    PYTHONPATH=build/python python3 examples/python/walkthrough.py [OUT_DIR]
`make test` runs it with the non-interactive backend (MPLBACKEND=Agg) and
checks what it prints.
"""
import os
import sys

import matplotlib
import matplotlib.pyplot as plt
import numpy as np

import estlab

out = sys.argv[1] if len(sys.argv) > 1 else '.'
os.makedirs(out, exist_ok=True)

# 1. Truth and measurements: y = sin(theta) + noise, 10 s at 80 Hz.
model = estlab.Model('pendulum')
truth = dict(g=9.81)
sim = estlab.simulate(model, t_end=10, dt=0.0125, x0=[0.785398, 0], params=truth,
                      process_noise=[1e-8, 1e-4], measure='sin', meas_noise=0.05, seed=7)
print('simulated  %d rows of %s' % (len(sim.t), ', '.join(sim.columns)))

# 2. Tune Q, R and g from a guess 10x off in the noise and 10 % off in g.
common = dict(kind='ukf', measure='sin', integrator='rk4', x0=[0.785398, 0], p0_diag=[1e-2, 1e-2])
tuned = estlab.tune(model, sim, params={'g': 8.8}, estimate_param=['g'],
                    init_q_diag=[1e-7, 1e-3], init_r_diag=0.5, **common)
g, se = tuned.params['g'], tuned.std_errors['g']
print('tuned      status %s, g = %.4f +- %.4f (truth 9.81), R = %.4g (truth 0.05)'
      % (tuned.status, g, se, tuned.r[0, 0]))
assert tuned.converged and abs(g - 9.81) < 3 * se

# 3. Filter and smooth with what the tuner found.
settings = dict(params={'g': g}, q=tuned.q, r=tuned.r, **common)
run = estlab.filter(model, sim, **settings)
smoothed = estlab.smooth(model, sim, **settings)
rmse = lambda r: np.sqrt(np.mean((r.x[:, 0] - sim['theta']) ** 2))
print('filter     theta RMSE %.4g, mean NIS %.3f (95%% bounds %.3f .. %.3f)'
      % (rmse(run), run.summary['mean_nis'], *run.summary['nis_bounds95']))
print('smoother   theta RMSE %.4g' % rmse(smoothed))
assert rmse(smoothed) < rmse(run)

# 4. A figure: the angle with the filter's 2-sigma band, and the innovations.
fig, (a, b) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
sd = np.sqrt(run.P[:, 0, 0])
a.fill_between(run.t, run.x[:, 0] - 2 * sd, run.x[:, 0] + 2 * sd, alpha=0.3, label='UKF +-2 sd')
a.plot(sim.t, sim['theta'], 'k', lw=1, label='truth')
a.plot(run.t, run.x[:, 0], label='UKF')
a.plot(smoothed.t, smoothed.x[:, 0], '--', label='URTS')
a.set_ylabel('theta [rad]')
a.legend(loc='upper right')
b.plot(run.t, run.nu[:, 0], lw=0.8)
b.plot(run.t, 2 * np.sqrt(run.S[:, 0, 0]), 'r', lw=0.8)
b.plot(run.t, -2 * np.sqrt(run.S[:, 0, 0]), 'r', lw=0.8)
b.set_ylabel('innovation')
b.set_xlabel('t [s]')
fig.tight_layout()
path = os.path.join(out, 'pendulum_python.png')
fig.savefig(path, dpi=90)
print('wrote      %s (backend %s)' % (path, matplotlib.get_backend()))
