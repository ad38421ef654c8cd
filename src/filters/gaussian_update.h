// What a Gaussian filter's measurement update produces, for any scalar T
// (double in the filters, ceres::Jet in the tuner's likelihood): the
// posterior (x+, P+), the gain that produced it, and the innovation nu with
// its covariance S = L L^T at the point the likelihood is taken (the prior;
// for the IEKF the first iteration).
//
// The filter classes turn it into a StepResult (SetInnovation); the tuner's
// likelihood whitens it (Whiten): the log-likelihood term is the same
// function of (nu, L) in both, so NLL = -(sum of the StepResult
// log-likelihoods) by construction.
#ifndef ESTLAB_FILTERS_GAUSSIAN_UPDATE_H_
#define ESTLAB_FILTERS_GAUSSIAN_UPDATE_H_

#include "src/core/types.h"

namespace estlab {

template <class T, int N, int M>
struct GaussianUpdate {
  Vec<T, N> x;         // x+
  MatT<T, N, N> P;     // P+
  MatT<T, N, M> K;     // the gain applied (IEKF: the last iteration's)
  Vec<T, M> nu;        // innovation at the prior, angle outputs wrapped
  MatT<T, M, M> S, L;  // its covariance S = L L^T
};

}  // namespace estlab

#endif  // ESTLAB_FILTERS_GAUSSIAN_UPDATE_H_
