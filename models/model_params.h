// Parameters of any scalar type: what `estlab tune --estimate-param` needs
// from a model to differentiate the filter through its physical parameters.
//
// A model opts in by declaring its parameters generic over the scalar S and
// taking them by a deduced type P in Rhs / Step and every measurement's Eval:
//
//   template <class S = double>
//   struct ParamsT {
//     S g = S(9.81);
//     S L = S(1.0);
//   };
//   using Params = ParamsT<>;
//   template <class T, class P>
//   static Vec<T, 2> Rhs(const T& t, const Vec<T, 2>& x, double u, const P& p);
//
// P is then either Params (double) or ParamsT<T> with T the state's scalar;
// hand-written code must not mix a double-typed temporary with p's members
// (write `auto` or T). The fields are read in declaration order, which must
// be the order of kParams, and Params must hold nothing else (checked by
// EstimableParams and ParamOrderMatches).
//
// Usage:
//   static_assert(EstimableParams<models::Pendulum>);
//   std::array<T, 3> v = ...;  // g, L, b
//   auto p = MakeParams<models::Pendulum>(v);           // ParamsT<T>
//   auto q = ParamsAs<models::Pendulum, S>(p);          // ParamsT<S>, or p itself
#ifndef ESTLAB_MODELS_MODEL_PARAMS_H_
#define ESTLAB_MODELS_MODEL_PARAMS_H_

#include <array>
#include <concepts>
#include <cstddef>
#include <type_traits>
#include <utility>

namespace estlab {

// Most parameters ParamValues can read (the arity of its structured bindings).
inline constexpr std::size_t kMaxEstimableParams = 16;

template <class M>
concept EstimableParams = requires {
  typename M::template ParamsT<double>;
}
&&std::same_as<typename M::template ParamsT<double>, typename M::Params> &&
    sizeof(typename M::Params) == M::kParams.size() * sizeof(double) &&
    M::kParams.size() <= kMaxEstimableParams;

// True when the fields of Model::Params are declared in the order of kParams
// (checked at run time: member pointers are not constant-comparable).
template <class Model>
bool ParamOrderMatches() {
  static const typename Model::Params p{};
  const char* base = reinterpret_cast<const char*>(&p);
  for (std::size_t i = 0; i < Model::kParams.size(); ++i) {
    const char* field = reinterpret_cast<const char*>(&(p.*(Model::kParams[i].member)));
    if (field != base + i * sizeof(double)) return false;
  }
  return true;
}

// ParamsT<S> from its field values in declaration order.
template <class Model, class S>
typename Model::template ParamsT<S> MakeParams(const std::array<S, Model::kParams.size()>& values) {
  return [&]<std::size_t... I>(std::index_sequence<I...>) {
    return typename Model::template ParamsT<S>{values[I]...};
  }
  (std::make_index_sequence<Model::kParams.size()>());
}

namespace model_params_internal {

// The fields of an aggregate of N members of one type, in declaration order.
template <std::size_t N, class P>
auto Fields(const P& p) {
#define ESTLAB_FIELDS(...)       \
  const auto& [__VA_ARGS__] = p; \
  return std::array{__VA_ARGS__};
  if constexpr (N == 1) {
    ESTLAB_FIELDS(a)
  } else if constexpr (N == 2) {
    ESTLAB_FIELDS(a, b)
  } else if constexpr (N == 3) {
    ESTLAB_FIELDS(a, b, c)
  } else if constexpr (N == 4) {
    ESTLAB_FIELDS(a, b, c, d)
  } else if constexpr (N == 5) {
    ESTLAB_FIELDS(a, b, c, d, e)
  } else if constexpr (N == 6) {
    ESTLAB_FIELDS(a, b, c, d, e, f)
  } else if constexpr (N == 7) {
    ESTLAB_FIELDS(a, b, c, d, e, f, g)
  } else if constexpr (N == 8) {
    ESTLAB_FIELDS(a, b, c, d, e, f, g, h)
  } else if constexpr (N == 9) {
    ESTLAB_FIELDS(a, b, c, d, e, f, g, h, i)
  } else if constexpr (N == 10) {
    ESTLAB_FIELDS(a, b, c, d, e, f, g, h, i, j)
  } else if constexpr (N == 11) {
    ESTLAB_FIELDS(a, b, c, d, e, f, g, h, i, j, k)
  } else if constexpr (N == 12) {
    ESTLAB_FIELDS(a, b, c, d, e, f, g, h, i, j, k, l)
  } else if constexpr (N == 13) {
    ESTLAB_FIELDS(a, b, c, d, e, f, g, h, i, j, k, l, m)
  } else if constexpr (N == 14) {
    ESTLAB_FIELDS(a, b, c, d, e, f, g, h, i, j, k, l, m, n)
  } else if constexpr (N == 15) {
    ESTLAB_FIELDS(a, b, c, d, e, f, g, h, i, j, k, l, m, n, o)
  } else {
    static_assert(N == 16, "at most kMaxEstimableParams parameters");
    ESTLAB_FIELDS(a, b, c, d, e, f, g, h, i, j, k, l, m, n, o, q)
  }
#undef ESTLAB_FIELDS
}

}  // namespace model_params_internal

// The field values of a ParamsT<X>, in declaration order.
template <class Model, class P>
auto ParamValues(const P& p) {
  return model_params_internal::Fields<Model::kParams.size()>(p);
}

// p as parameters of scalar S: p itself when it is double Params or already
// ParamsT<S>, else ParamsT<S> with each field S(value) (a Jet's value becomes
// the scalar part of a nested Jet).
template <class Model, class S, class P>
decltype(auto) ParamsAs(const P& p) {
  if constexpr (std::is_same_v<P, typename Model::Params>) {
    return (p);
  } else if constexpr (std::is_same_v<P, typename Model::template ParamsT<S>>) {
    return (p);
  } else {
    const auto values = ParamValues<Model>(p);
    std::array<S, Model::kParams.size()> lifted;
    for (std::size_t i = 0; i < lifted.size(); ++i) lifted[i] = S(values[i]);
    return MakeParams<Model, S>(lifted);
  }
}

}  // namespace estlab

#endif  // ESTLAB_MODELS_MODEL_PARAMS_H_
