// The registration of the filter kinds: their names, their options structs
// (one std::variant alternative each) and whether the tuner can
// differentiate them. A light header: only the options structs.
//
// Adding a filter kind "foo" (a dry run, the files it touches):
//   1. src/filters/foo.h: the filter class, a FooOptions struct with
//      IsValid(std::string*) and IsValidFor(int n, std::string*), and the
//      MakeFilterFor(const FooOptions&, ...) overload that builds it; listed
//      in src/filters/filters.h.
//   2. Its registration: the enum value, the variant alternative and the row
//      of kFilterKinds below (filter_kinds.cpp), and FooOptions' keys in the
//      key table (src/options/filter_settings.cpp).
//   3. Its test: tests/filters/foo_test.cpp, against the hand-written
//      Kalman reference of tests/filters/linear_fixture.h.
// std::visit over FilterKindOptions is exhaustive: a kind with no
// MakeFilterFor, or no case in the likelihood when it is tunable, is a
// compile error, never a silent fallback to another kind.
//
// Usage:
//   FilterSpec spec;
//   spec.filter = EkfOptions{.iterations = 3};       // an IEKF
//   FilterKindName(KindOf(spec.filter));             // "ekf"
//   spec.filter = DefaultFilterOptions(ParseFilterKind("ghkf"));
#ifndef ESTLAB_RUN_FILTER_KINDS_H_
#define ESTLAB_RUN_FILTER_KINDS_H_

#include <string>
#include <variant>
#include <vector>

#include "src/filters/filter_options.h"

namespace estlab {

enum class FilterKind { kKf, kEkf, kUkf, kCkf, kGhkf, kPf };

// One options struct per filter kind; the sigma-point kinds share
// SigmaPointOptions and differ in its rule.
using FilterKindOptions = std::variant<KfOptions, EkfOptions, SigmaPointOptions, ParticleOptions>;

struct FilterKindInfo {
  FilterKind kind;
  const char* name;
  bool tunable;  // the tuner differentiates its likelihood (adaptive/likelihood.h)
};

// Every kind, in help order.
const std::vector<FilterKindInfo>& FilterKinds();
const FilterKindInfo& InfoOf(FilterKind kind);

// kf | ekf | iekf | ukf | ckf | ghkf | pf (iekf = ekf with iterations);
// throws InputError naming the kinds.
FilterKind ParseFilterKind(const std::string& name);
const char* FilterKindName(FilterKind kind);
// The kind an options value runs (the rule, for sigma-point options).
FilterKind KindOf(const FilterKindOptions& options);
// The kind's options with their defaults (the rule set for sigma-point kinds).
FilterKindOptions DefaultFilterOptions(FilterKind kind);

}  // namespace estlab

#endif  // ESTLAB_RUN_FILTER_KINDS_H_
