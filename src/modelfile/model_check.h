// Second pass of ParseModelFile: the cross-reference checks of a RawModel
// (model_reader.h). Reports missing parts (name, states, measurements, [rhs]
// or [step]), names defined twice or reserved (t, dt, pi, function names),
// equations for non-states and states without one, and resolves every name
// in every expression according to where it is used (model_file.h lists what
// each section may use), with "did you mean" suggestions. Fills in
// raw->model.rhs (state order), raw->model.discrete and Expr::ref/index.
//
// Usage:
//   CheckModel(&raw, &problems);
//   if (problems.empty()) return std::move(raw.model);
#ifndef ESTLAB_MODELFILE_MODEL_CHECK_H_
#define ESTLAB_MODELFILE_MODEL_CHECK_H_

#include <vector>

#include "src/modelfile/diagnostic.h"
#include "src/modelfile/model_reader.h"

namespace estlab::modelfile {

void CheckModel(RawModel* raw, std::vector<Diagnostic>* diagnostics);

}  // namespace estlab::modelfile

#endif  // ESTLAB_MODELFILE_MODEL_CHECK_H_
