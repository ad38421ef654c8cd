#include "src/run/filter_kinds.h"

#include <type_traits>

#include "src/core/types.h"

namespace estlab {

const std::vector<FilterKindInfo>& FilterKinds() {
  static const std::vector<FilterKindInfo> kinds = {
      {FilterKind::kKf, "kf", true},     {FilterKind::kEkf, "ekf", true},
      {FilterKind::kUkf, "ukf", true},   {FilterKind::kCkf, "ckf", true},
      {FilterKind::kGhkf, "ghkf", true}, {FilterKind::kPf, "pf", false},
  };
  return kinds;
}

const FilterKindInfo& InfoOf(FilterKind kind) {
  for (const FilterKindInfo& info : FilterKinds())
    if (info.kind == kind) return info;
  throw InputError("unregistered filter kind");  // a kind missing from FilterKinds()
}

FilterKind ParseFilterKind(const std::string& name) {
  if (name == "iekf") return FilterKind::kEkf;
  std::string names;
  for (const FilterKindInfo& info : FilterKinds()) {
    if (name == info.name) return info.kind;
    names += std::string(names.empty() ? "" : ", ") + info.name +
             (info.kind == FilterKind::kEkf ? ", iekf" : "");
  }
  throw InputError("unknown filter '" + name + "' (expected " + names + ")");
}

const char* FilterKindName(FilterKind kind) { return InfoOf(kind).name; }

FilterKind KindOf(const FilterKindOptions& options) {
  return std::visit(
      [](const auto& o) {
        using O = std::decay_t<decltype(o)>;
        if constexpr (std::is_same_v<O, KfOptions>) {
          return FilterKind::kKf;
        } else if constexpr (std::is_same_v<O, EkfOptions>) {
          return FilterKind::kEkf;
        } else if constexpr (std::is_same_v<O, ParticleOptions>) {
          return FilterKind::kPf;
        } else {
          static_assert(std::is_same_v<O, SigmaPointOptions>,
                        "a FilterKindOptions alternative has no kind");
          switch (o.rule) {
            case SigmaRule::kUnscented:
              return FilterKind::kUkf;
            case SigmaRule::kCubature:
              return FilterKind::kCkf;
            case SigmaRule::kGaussHermite:
              return FilterKind::kGhkf;
          }
          return FilterKind::kUkf;  // not reached: the switch is exhaustive
        }
      },
      options);
}

FilterKindOptions DefaultFilterOptions(FilterKind kind) {
  switch (kind) {
    case FilterKind::kKf:
      return KfOptions{};
    case FilterKind::kEkf:
      return EkfOptions{};
    case FilterKind::kUkf:
      return SigmaPointOptions{.rule = SigmaRule::kUnscented};
    case FilterKind::kCkf:
      return SigmaPointOptions{.rule = SigmaRule::kCubature};
    case FilterKind::kGhkf:
      return SigmaPointOptions{.rule = SigmaRule::kGaussHermite};
    case FilterKind::kPf:
      return ParticleOptions{};
  }
  throw InputError("unregistered filter kind");
}

}  // namespace estlab
