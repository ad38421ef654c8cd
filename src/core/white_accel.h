// The white-noise-acceleration process noise, written once: for each
// (position, rate) pair of states, a continuous white acceleration of
// spectral density qc integrated over a step dt gives
//   Q[pos, pos] = qc dt^3 / 3,  Q[pos, rate] = Q[rate, pos] = qc dt^2 / 2,
//   Q[rate, rate] = qc dt,
// zero elsewhere. Used by the filter runs, the tuner's white-accel Q(theta)
// and the studies' truth.
//
// Usage:
//   Mat<4, 4> Q;
//   FillWhiteAccel(Model::kPositionRatePairs, qc, dt, &Q);   // any Eigen matrix
#ifndef ESTLAB_CORE_WHITE_ACCEL_H_
#define ESTLAB_CORE_WHITE_ACCEL_H_

namespace estlab {

// *Q (already sized n x n) <- qc Q_wa(dt) on `pairs` (a range of
// std::pair<int, int>).
template <class Pairs, class Matrix>
void FillWhiteAccel(const Pairs& pairs, double qc, double dt, Matrix* Q) {
  Q->setZero();
  for (const auto& [pos, rate] : pairs) {
    (*Q)(pos, pos) = qc * dt * dt * dt / 3.0;
    (*Q)(pos, rate) = (*Q)(rate, pos) = qc * dt * dt / 2.0;
    (*Q)(rate, rate) = qc * dt;
  }
}

}  // namespace estlab

#endif  // ESTLAB_CORE_WHITE_ACCEL_H_
