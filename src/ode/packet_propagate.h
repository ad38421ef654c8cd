// FixedPropagatePoints: a point set (one point per column) through the fixed
// step integrators kPacketWidth points per call, for models that may be
// evaluated on packets (src/core/packet.h, kPacketModel).
//
// Usage (FixedStepTransition::StepCloud does this):
//   FixedPropagatePoints<models::Pendulum>(Integrator::kRk4, points, t0, t1, substeps, u,
//                                          params, &moved);
//
// Lane k of packet j holds column j * kPacketWidth + k; the last packet is
// padded with copies of the last column, so every column takes the same
// arithmetic whatever the count, and a column's result does not depend on
// its neighbours. `out` must already have points.cols() columns.
#ifndef ESTLAB_ODE_PACKET_PROPAGATE_H_
#define ESTLAB_ODE_PACKET_PROPAGATE_H_

#include <algorithm>

#include "src/core/packet.h"
#include "src/core/types.h"
#include "src/ode/fixed_step.h"

namespace estlab {

// Lanes of columns first .. first + kPacketWidth - 1 of `points` (the last
// column repeated past the end).
template <int N>
Vec<Packet, N> GatherColumns(const Eigen::Matrix<double, N, Eigen::Dynamic>& points,
                             Eigen::Index first) {
  const Eigen::Index last = points.cols() - 1;
  Vec<Packet, N> x;
  for (int k = 0; k < kPacketWidth; ++k) {
    const Eigen::Index col = std::min<Eigen::Index>(first + k, last);
    for (int i = 0; i < N; ++i) x(i).Set(k, points(i, col));
  }
  return x;
}

// Writes the lanes of x that fall inside `points` to columns first, first + 1, ...
template <int N>
void ScatterColumns(const Vec<Packet, N>& x, Eigen::Index first,
                    Eigen::Matrix<double, N, Eigen::Dynamic>* points) {
  const int lanes = int(std::min<Eigen::Index>(kPacketWidth, points->cols() - first));
  for (int k = 0; k < lanes; ++k)
    for (int i = 0; i < N; ++i) (*points)(i, first + k) = x(i)[k];
}

template <class Model, class Prm>
void FixedPropagatePoints(Integrator scheme,
                          const Eigen::Matrix<double, Model::kStateDim, Eigen::Dynamic>& points,
                          double t0, double t1, int substeps, const InputPath<Model>& u,
                          const Prm& p,
                          Eigen::Matrix<double, Model::kStateDim, Eigen::Dynamic>* out) {
  constexpr int kN = Model::kStateDim;
  for (Eigen::Index first = 0; first < points.cols(); first += kPacketWidth) {
    const Vec<Packet, kN> x = GatherColumns<kN>(points, first);
    ScatterColumns<kN>(FixedPropagate<Model, Packet, Prm>(scheme, x, t0, t1, substeps, u, p), first,
                       out);
  }
}

}  // namespace estlab

#endif  // ESTLAB_ODE_PACKET_PROPAGATE_H_
