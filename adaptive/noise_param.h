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
//   blockwise    R = blockdiag(R_g), one block per sensor group, each of
//                the kinds above but white-accel (CovarianceBlock)
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

// One diagonal block of a blockwise covariance (one sensor group's R):
// rows and columns [first, first + count) with their own parameterisation
// (diag, full, scalar or fixed); the entries between blocks are 0.
struct CovarianceBlock {
  NoiseParam kind = NoiseParam::kDiag;
  int first = 0;
  int count = 0;
  std::string label;  // the group's name, for scalar parameters ("log r_imu")
};

template <int D>
class CovarianceParam {
 public:
  // `symbol` is "q" or "r" (for names and messages), `component_names` the
  // state or output names, `pairs` the (position, rate) pairs for white-accel,
  // `dt_ref` the step at which a white-accel initial value is turned into a
  // matrix for the other parameterisations. `blocks` (R only): one per sensor
  // group, covering 0..D-1 in order; empty: one block of `kind`. Throws
  // InputError when a kind does not fit the initial value.
  CovarianceParam(NoiseParam kind, const std::string& symbol,
                  const std::vector<std::string>& component_names,
                  const std::vector<std::pair<int, int>>& pairs,
                  const InitialCovariance<D>& initial, double dt_ref,
                  std::vector<CovarianceBlock> blocks = {})
      : kind_(kind),
        symbol_(symbol),
        names_(component_names),
        pairs_(pairs),
        initial_(initial),
        blocks_(std::move(blocks)) {
    const std::string what = symbol == "q" ? "Q" : "R";
    const Mat<D, D> m0 = initial.white_accel ? WhiteAccel(initial.qc, dt_ref) : initial.matrix;
    if (!m0.allFinite()) throw InputError("the initial " + what + " is not finite");
    if (kind == NoiseParam::kWhiteAccel) {
      if (pairs.empty()) {
        throw InputError(
            "white-accel applies to the process noise Q only (it needs the "
            "model's position/rate pairs)");
      }
      if (!initial.white_accel || !(initial.qc > 0)) {
        throw InputError("white-accel tuning of Q needs an initial qc > 0 (--init-q-white-accel)");
      }
      theta0_.push_back(std::log(initial.qc));
      AddName("log qc", true);
      return;
    }
    // One block, or all diag or all fixed blocks: that kind over the whole
    // matrix (EM and ALS take it); all fixed keeps 0 between the groups.
    bool same = !blocks_.empty();
    for (const CovarianceBlock& b : blocks_)
      same = same && b.kind == blocks_.front().kind &&
             (blocks_.size() == 1 || b.kind == NoiseParam::kDiag || b.kind == NoiseParam::kFixed);
    if (same) {
      kind_ = blocks_.front().kind;
      if (kind_ == NoiseParam::kFixed) ZeroBetweenBlocks(&initial_.matrix);
    }
    if (same || blocks_.empty()) blocks_.assign(1, {kind_, 0, D, ""});
    int next = 0;
    for (const CovarianceBlock& b : blocks_) {
      if (b.first != next || b.count < 1 || b.kind == NoiseParam::kWhiteAccel)
        throw InputError("the blocks of " + what + " must cover it in order (internal)");
      next += b.count;
      AddBlock(b, what, m0);
    }
    if (next != D) throw InputError("the blocks of " + what + " must cover it (internal)");
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
    if (kind_ == NoiseParam::kWhiteAccel)
      return exp(theta[0]) * WhiteAccel(1.0, dt).template cast<T>();
    if (kind_ == NoiseParam::kFixed && blocks_.size() == 1)
      return (initial_.white_accel ? WhiteAccel(initial_.qc, dt) : initial_.matrix)
          .template cast<T>();
    MatT out = MatT::Zero();
    MatT L = MatT::Zero();  // the full blocks' Cholesky factors
    bool any_full = false;
    int k = 0;
    for (const CovarianceBlock& b : blocks_) {
      const int e = b.first + b.count;
      switch (b.kind) {
        case NoiseParam::kDiag:
          for (int i = b.first; i < e; ++i) out(i, i) = exp(theta[k++]);
          break;
        case NoiseParam::kFull:
          any_full = true;
          for (int i = b.first; i < e; ++i) {
            for (int j = b.first; j < i; ++j) L(i, j) = theta[k++];
            L(i, i) = exp(0.5 * theta[k++]);
          }
          break;
        case NoiseParam::kScalar: {
          const T v = exp(theta[k++]);
          for (int i = b.first; i < e; ++i) out(i, i) = v;
          break;
        }
        case NoiseParam::kFixed:
        default:
          out.block(b.first, b.first, b.count, b.count) =
              initial_.matrix.block(b.first, b.first, b.count, b.count).template cast<T>();
          break;
      }
    }
    if (any_full) out += L * L.transpose();  // the blocks are disjoint: blockdiag(L_b L_b^T)
    return out;
  }

  // The blocks: one per sensor group, or one of kind() over all of D.
  const std::vector<CovarianceBlock>& Blocks() const { return blocks_; }
  // True when the blocks differ from one block of kind() (EM and ALS take
  // one kind over the whole matrix).
  bool Blockwise() const { return blocks_.size() > 1; }

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
  // The lower Cholesky factor of block b of m0 (fixed-size for the whole
  // matrix, as before blocks existed); empty when it is not positive
  // definite.
  static Eigen::MatrixXd BlockCholesky(const CovarianceBlock& b, const Mat<D, D>& m0) {
    if (b.count == D) {
      const Eigen::LLT<Mat<D, D>> llt(m0);
      if (llt.info() != Eigen::Success || !(m0.diagonal().minCoeff() > 0)) return {};
      return Mat<D, D>(llt.matrixL());
    }
    const Eigen::MatrixXd block = m0.block(b.first, b.first, b.count, b.count);
    const Eigen::LLT<Eigen::MatrixXd> llt(block);
    if (llt.info() != Eigen::Success || !(block.diagonal().minCoeff() > 0)) return {};
    return llt.matrixL();
  }

  // m's entries between different blocks set to 0.
  void ZeroBetweenBlocks(Mat<D, D>* m) const {
    for (const CovarianceBlock& a : blocks_)
      for (const CovarianceBlock& b : blocks_)
        if (a.first != b.first) m->block(a.first, b.first, a.count, b.count).setZero();
  }

  // The initial parameters and names of block b of the initial matrix m0.
  void AddBlock(const CovarianceBlock& b, const std::string& what, const Mat<D, D>& m0) {
    const int e = b.first + b.count;
    switch (b.kind) {
      case NoiseParam::kDiag:
        for (int i = b.first; i < e; ++i) {
          if (!(m0(i, i) > 0)) {
            throw InputError("diag tuning of " + what + " needs a positive initial diagonal, got " +
                             what + "(" + names_[i] + ", " + names_[i] +
                             ") = " + FormatNumber(m0(i, i)));
          }
          theta0_.push_back(std::log(m0(i, i)));
          AddName("log " + symbol_ + "_" + names_[i], true);
        }
        break;
      case NoiseParam::kFull: {
        const Eigen::MatrixXd L = BlockCholesky(b, m0);
        if (L.size() == 0) {
          throw InputError("full (log-Cholesky) tuning of " + what +
                           (b.label.empty() ? "" : " (group " + b.label + ")") +
                           " needs a positive definite initial matrix");
        }
        for (int i = 0; i < b.count; ++i) {
          const std::string& ni = names_[b.first + i];
          for (int j = 0; j < i; ++j) {
            theta0_.push_back(L(i, j));
            AddName("L" + symbol_ + "(" + ni + "," + names_[b.first + j] + ")", false);
            off_row_.back() = b.first + i;
          }
          theta0_.push_back(std::log(L(i, i) * L(i, i)));
          AddName("log L" + symbol_ + "(" + ni + "," + ni + ")^2", true);
        }
        break;
      }
      case NoiseParam::kScalar: {
        const double sc = m0.block(b.first, b.first, b.count, b.count).trace() / b.count;
        if (!(sc > 0)) {
          throw InputError("scalar tuning of " + what +
                           (b.label.empty() ? "" : " (group " + b.label + ")") +
                           " needs trace > 0");
        }
        theta0_.push_back(std::log(sc));
        AddName("log " + symbol_ + (b.label.empty() ? "" : "_" + b.label), true);
        break;
      }
      case NoiseParam::kFixed:
      default:
        break;
    }
  }

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
  std::vector<CovarianceBlock> blocks_;
};

}  // namespace estlab

#endif  // ESTLAB_ADAPTIVE_NOISE_PARAM_H_
