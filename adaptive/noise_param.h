// Covariance parameterisations of the likelihood tuner: a D x D covariance
// (Q or R) as a function of a few unconstrained parameters theta, for any
// scalar type (double, ceres::Jet).
//
//   diag         D = diag(exp(theta_i))
//   full         D = L L^T, L lower triangular, L_ii = exp(theta_ii / 2),
//                L_ij = theta_ij (i > j); theta in row-major lower order
//   white-accel  D = exp(theta) Q_wa(dt), Q_wa = [[dt^3/3, dt^2/2],
//                [dt^2/2, dt]] on each (position, rate) pair
//   scalar       D = exp(theta) I
//   fixed        D = the initial matrix (or qc Q_wa(dt)), no parameters
//
// Usage:
//   CovarianceParam<2> q(NoiseParam::kWhiteAccel, "q", names, pairs, initial);
//   std::vector<double> theta0 = q.InitialTheta();
//   Eigen::Matrix<T, 2, 2> Q = q.Matrix<T>(theta0.data(), dt);
#ifndef ESTLAB_ADAPTIVE_NOISE_PARAM_H_
#define ESTLAB_ADAPTIVE_NOISE_PARAM_H_

#include <Eigen/Cholesky>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "adaptive/tuner.h"
#include "src/core/types.h"
#include "src/core/white_accel.h"

namespace estlab {

// The initial value of a covariance: a matrix, or qc times the
// white-noise-acceleration shape (process noise only).
template <int D>
struct InitialCovariance {
  Mat<D, D> matrix = Mat<D, D>::Zero();
  bool white_accel = false;
  double qc = 0.0;
};

template <int D>
class CovarianceParam {
 public:
  // `symbol` is "q" or "r" (for names and messages), `component_names` the
  // state or output names, `pairs` the (position, rate) pairs for white-accel,
  // `dt_ref` the step at which a white-accel initial value is turned into a
  // matrix for the other parameterisations. Throws InputError when `kind`
  // does not fit the initial value.
  CovarianceParam(NoiseParam kind, const std::string& symbol,
                  const std::vector<std::string>& component_names,
                  const std::vector<std::pair<int, int>>& pairs,
                  const InitialCovariance<D>& initial, double dt_ref)
      : kind_(kind), symbol_(symbol), names_(component_names), pairs_(pairs), initial_(initial) {
    const std::string what = symbol == "q" ? "Q" : "R";
    const Mat<D, D> m0 = initial.white_accel ? WhiteAccel(initial.qc, dt_ref) : initial.matrix;
    if (!m0.allFinite()) throw InputError("the initial " + what + " is not finite");
    switch (kind) {
      case NoiseParam::kDiag:
        for (int i = 0; i < D; ++i) {
          if (!(m0(i, i) > 0)) {
            throw InputError("diag tuning of " + what + " needs a positive initial diagonal, got " +
                             what + "(" + names_[i] + ", " + names_[i] +
                             ") = " + FormatNumber(m0(i, i)));
          }
          theta0_.push_back(std::log(m0(i, i)));
          AddName("log " + symbol + "_" + names_[i], true);
        }
        break;
      case NoiseParam::kFull: {
        const Eigen::LLT<Mat<D, D>> llt(m0);
        if (llt.info() != Eigen::Success || !(m0.diagonal().minCoeff() > 0)) {
          throw InputError("full (log-Cholesky) tuning of " + what +
                           " needs a positive definite initial matrix");
        }
        const Mat<D, D> L = llt.matrixL();
        for (int i = 0; i < D; ++i) {
          for (int j = 0; j < i; ++j) {
            theta0_.push_back(L(i, j));
            AddName("L" + symbol + "(" + names_[i] + "," + names_[j] + ")", false);
            off_row_.back() = i;
          }
          theta0_.push_back(std::log(L(i, i) * L(i, i)));
          AddName("log L" + symbol + "(" + names_[i] + "," + names_[i] + ")^2", true);
        }
        break;
      }
      case NoiseParam::kWhiteAccel:
        if (pairs.empty()) {
          throw InputError(
              "white-accel applies to the process noise Q only (it needs the "
              "model's position/rate pairs)");
        }
        if (!initial.white_accel || !(initial.qc > 0)) {
          throw InputError(
              "white-accel tuning of Q needs an initial qc > 0 (--init-q-white-accel)");
        }
        theta0_.push_back(std::log(initial.qc));
        AddName("log qc", true);
        break;
      case NoiseParam::kScalar: {
        const double s = m0.trace() / D;
        if (!(s > 0)) throw InputError("scalar tuning of " + what + " needs trace > 0");
        theta0_.push_back(std::log(s));
        AddName("log " + symbol, true);
        break;
      }
      case NoiseParam::kFixed:
        break;
    }
  }

  NoiseParam kind() const { return kind_; }
  int NumParams() const { return int(theta0_.size()); }
  const std::vector<double>& InitialTheta() const { return theta0_; }
  const std::vector<std::string>& Names() const { return param_names_; }
  const std::vector<bool>& IsLog() const { return is_log_; }
  // For each parameter: the row i of an off-diagonal Cholesky entry L_ij,
  // -1 for log parameters.
  const std::vector<int>& OffDiagonalRow() const { return off_row_; }
  // Whether Matrix() depends on the step dt (white-accel, or fixed with a
  // white-accel initial value).
  bool DependsOnDt() const {
    return kind_ == NoiseParam::kWhiteAccel ||
           (kind_ == NoiseParam::kFixed && initial_.white_accel);
  }
  bool IsWhiteAccel() const { return DependsOnDt(); }

  // The covariance for parameters theta (NumParams() of them) and step dt.
  template <class T>
  Eigen::Matrix<T, D, D> Matrix(const T* theta, double dt) const {
    using std::exp;
    using MatT = Eigen::Matrix<T, D, D>;
    MatT out = MatT::Zero();
    switch (kind_) {
      case NoiseParam::kDiag:
        for (int i = 0; i < D; ++i) out(i, i) = exp(theta[i]);
        return out;
      case NoiseParam::kFull: {
        MatT L = MatT::Zero();
        int k = 0;
        for (int i = 0; i < D; ++i) {
          for (int j = 0; j < i; ++j) L(i, j) = theta[k++];
          L(i, i) = exp(0.5 * theta[k++]);
        }
        out = L * L.transpose();
        return out;
      }
      case NoiseParam::kWhiteAccel:
        return exp(theta[0]) * WhiteAccel(1.0, dt).template cast<T>();
      case NoiseParam::kScalar:
        for (int i = 0; i < D; ++i) out(i, i) = exp(theta[0]);
        return out;
      case NoiseParam::kFixed:
      default:
        return (initial_.white_accel ? WhiteAccel(initial_.qc, dt) : initial_.matrix)
            .template cast<T>();
    }
  }

  // qc for white-accel (or fixed with a white-accel initial value), else 0.
  double Qc(const double* theta) const {
    if (kind_ == NoiseParam::kWhiteAccel) return std::exp(theta[0]);
    if (kind_ == NoiseParam::kFixed && initial_.white_accel) return initial_.qc;
    return 0.0;
  }

  Mat<D, D> WhiteAccel(double qc, double dt) const {
    Mat<D, D> Q;
    FillWhiteAccel(pairs_, qc, dt, &Q);
    return Q;
  }

 private:
  void AddName(const std::string& name, bool is_log) {
    param_names_.push_back(name);
    is_log_.push_back(is_log);
    off_row_.push_back(-1);
  }

  NoiseParam kind_;
  std::string symbol_;
  std::vector<std::string> names_;
  std::vector<std::pair<int, int>> pairs_;
  InitialCovariance<D> initial_;
  std::vector<double> theta0_;
  std::vector<std::string> param_names_;
  std::vector<bool> is_log_;
  std::vector<int> off_row_;
};

}  // namespace estlab

#endif  // ESTLAB_ADAPTIVE_NOISE_PARAM_H_
