// Initial states estimated as parameters (--estimate-x0): which states, one
// x0 shared by every dataset or each dataset its own (--x0-per-file), their
// theta names and where they sit in theta. One rule for both fits that
// estimate x0: the prediction-error fit (x0 is the filter's prior mean,
// adaptive/likelihood.h) and the output-error fit (x0 is where the free
// simulation starts, studies/run/output_error.h).
//
//   theta slice = [row 0: x0[i_1] .. x0[i_k] | row 1: ... ]   natural scale,
//                 unbounded; one row, or one per dataset (per_file)
//   names       = "x0 h1" (shared), "x0[2] h1" (dataset 2's, from 1)
//
// Usage:
//   const InitialStates x0 = ResolveInitialStates({"h1"}, false, runs.size(), states, "tanks");
//   x0.Apply(theta + first, dataset, &x);   // x[i_j] = theta of its row
#ifndef ESTLAB_ADAPTIVE_INITIAL_STATES_H_
#define ESTLAB_ADAPTIVE_INITIAL_STATES_H_

#include <cstddef>
#include <string>
#include <vector>

namespace estlab {

struct InitialStates {
  std::vector<int> index;  // the estimated states, in the order named
  int rows = 0;            // 0 (none estimated), 1 (shared), or one per dataset

  bool empty() const { return index.empty(); }
  int NumParams() const { return int(index.size()) * rows; }
  // The row of theta that dataset `dataset` starts from.
  int RowOf(std::size_t dataset) const { return rows > 1 ? int(dataset) : 0; }
  // The theta names of the slice, row by row.
  std::vector<std::string> Names(const std::vector<std::string>& states) const;

  // x with the estimated components of dataset `dataset` taken from the
  // slice (theta points at its first entry); x is an Eigen vector of T.
  template <class T, class Vec>
  void Apply(const T* theta, std::size_t dataset, Vec* x) const {
    const T* row = theta + RowOf(dataset) * int(index.size());
    for (std::size_t j = 0; j < index.size(); ++j) (*x)(index[j]) = row[j];
  }
};

// The estimated states `names` of a model with states `states`; InputError
// for a name that is not a state (listing them), a state named twice, an
// empty name, or per_file without names or with fewer than two datasets.
InitialStates ResolveInitialStates(const std::vector<std::string>& names, bool per_file,
                                   std::size_t datasets, const std::vector<std::string>& states,
                                   const std::string& model);

}  // namespace estlab

#endif  // ESTLAB_ADAPTIVE_INITIAL_STATES_H_
