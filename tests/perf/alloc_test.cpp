// Allocation-free filter steps (issue "Performance"): global operator new and
// delete are replaced in this test program by counting versions, and the
// fixed-size Gaussian filters (KF, EKF, UKF, CKF, GHKF) must not allocate
// inside Predict and Update over 1000 steps with RK4 transitions, for the
// pendulum (n = 2, m = 1) and the double pendulum (n = 4, m = 2).
//
// Eigen's dynamic matrices allocate with malloc, not operator new, so malloc,
// calloc, realloc and the aligned variants are replaced too (glibc: they
// forward to __libc_malloc & co.; not under AddressSanitizer, which owns
// malloc - there only operator new is counted). Every StepResult is handed
// to a function the compiler cannot see through, so no allocation is
// optimised away.
//
// This file is its own test program (perf_alloc_tests): replacing operator
// new would otherwise count every other test's allocations too.
#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <limits>
#include <memory>
#include <new>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "models/double_pendulum.h"
#include "models/pendulum.h"
#include "src/core/params.h"
#include "src/filters/ekf.h"
#include "src/filters/kalman.h"
#include "src/filters/particle.h"
#include "src/filters/sigma_point.h"
#include "src/ode/transition_impl.h"

namespace {

// Allocations made while counting is on (any thread).
std::atomic<bool> g_counting{false};
std::atomic<long> g_allocations{0};

void Count() {
  if (g_counting.load(std::memory_order_relaxed))
    g_allocations.fetch_add(1, std::memory_order_relaxed);
}

}  // namespace

#if !defined(__SANITIZE_ADDRESS__)
#define ESTLAB_COUNT_MALLOC 1
extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* __libc_memalign(std::size_t, std::size_t);
void __libc_free(void*);

void* malloc(std::size_t size) noexcept {
  Count();
  return __libc_malloc(size);
}
void* calloc(std::size_t count, std::size_t size) noexcept {
  Count();
  return __libc_calloc(count, size);
}
void* realloc(void* p, std::size_t size) noexcept {
  Count();
  return __libc_realloc(p, size);
}
void* memalign(std::size_t alignment, std::size_t size) noexcept {
  Count();
  return __libc_memalign(alignment, size);
}
void* aligned_alloc(std::size_t alignment, std::size_t size) noexcept {
  Count();
  return __libc_memalign(alignment, size);
}
int posix_memalign(void** out, std::size_t alignment, std::size_t size) noexcept {
  Count();
  *out = __libc_memalign(alignment, size);
  return *out != nullptr ? 0 : ENOMEM;
}
void free(void* p) noexcept { __libc_free(p); }
}
#endif

namespace {

// This file's operator new allocates with malloc, so its operator delete
// frees with free: GCC's -Wmismatched-new-delete (an error with -Werror, seen
// in the -O1 sanitizer build where the calls are inlined) does not apply.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"

// operator new: counted here, or by malloc when malloc is replaced.
void* CountedAlloc(std::size_t size, std::size_t alignment) {
#if !defined(ESTLAB_COUNT_MALLOC)
  Count();
#endif
  if (size == 0) size = 1;
  void* p = nullptr;
  if (alignment <= alignof(std::max_align_t)) {
    p = std::malloc(size);
  } else {
    // aligned_alloc needs a size that is a multiple of the alignment.
    p = std::aligned_alloc(alignment, (size + alignment - 1) / alignment * alignment);
  }
  return p;
}

}  // namespace

void* operator new(std::size_t size) {
  if (void* p = CountedAlloc(size, 0)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) {
  if (void* p = CountedAlloc(size, 0)) return p;
  throw std::bad_alloc();
}
void* operator new(std::size_t size, std::align_val_t a) {
  if (void* p = CountedAlloc(size, std::size_t(a))) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size, std::align_val_t a) {
  if (void* p = CountedAlloc(size, std::size_t(a))) return p;
  throw std::bad_alloc();
}
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  return CountedAlloc(size, 0);
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
  return CountedAlloc(size, 0);
}
void* operator new(std::size_t size, std::align_val_t a, const std::nothrow_t&) noexcept {
  return CountedAlloc(size, std::size_t(a));
}
void* operator new[](std::size_t size, std::align_val_t a, const std::nothrow_t&) noexcept {
  return CountedAlloc(size, std::size_t(a));
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }

namespace estlab {
namespace {

using models::DoublePendulum;
using models::Pendulum;

constexpr int kSteps = 1000;
constexpr double kDt = 0.01;

// Counts the allocations made between construction and Stop().
class AllocationCounter {
 public:
  AllocationCounter() {
    g_allocations.store(0);
    g_counting.store(true);
  }
  ~AllocationCounter() { g_counting.store(false); }
  long Stop() {
    g_counting.store(false);
    return g_allocations.load();
  }
};

// A cart driven by a motor voltage V and a load force F (two inputs), its
// position and motor current measured; the current sees V (h(x, u)).
struct DcCart {
  static constexpr const char* kName = "dc-cart-alloc";
  static constexpr const char* kDescription = "two inputs, h(x, u)";
  static constexpr int kStateDim = 2;
  static constexpr int kInputDim = 2;
  static constexpr std::array<const char*, 2> kInputNames = {"V", "F"};
  static constexpr std::array<const char*, 2> kInputUnits = {"V", "N"};
  static constexpr bool kStiff = false;
  static constexpr std::array<const char*, 2> kStateNames = {"x", "v"};
  static constexpr std::array<const char*, 2> kStateUnits = {"m", "m/s"};
  static constexpr std::array<bool, 2> kAngleStates = {false, false};
  static constexpr std::array<std::pair<int, int>, 1> kPositionRatePairs = {{{0, 1}}};
  struct Params {
    double m = 2.0, b = 3.0, K = 0.05, R = 1.5, r = 0.02;
  };
  static constexpr std::array<ParamSpec<Params>, 1> kParams = {
      {{"m", &Params::m, "mass [kg]", Constraint::kPositive}}};
  template <class T>
  static Vec<T, 2> Rhs(const T&, const Vec<T, 2>& x, const Vec<double, 2>& u, const Params& p) {
    const T i = (u(0) - p.K * x(1) / p.r) / p.R;
    return Vec<T, 2>(x(1), (p.K * i / p.r - p.b * x(1) + u(1)) / p.m);
  }
  static constexpr std::array<const char*, 0> kInvariantNames = {};
  static bool InvariantsHold(const Params&, const Vec<double, 2>&) { return false; }
  static Vec<double, 0> Invariants(const Vec<double, 2>&, const Params&) { return {}; }
  struct EncoderCurrent {
    static constexpr const char* kName = "encoder-current";
    static constexpr int kDim = 2;
    static constexpr std::array<const char*, 2> kOutputs = {"x", "current"};
    static constexpr std::array<bool, 2> kAngleOutputs = {false, false};
    template <class T>
    static Vec<T, 2> Eval(const Vec<T, 2>& x, const Vec<double, 2>& u, const Params& p) {
      return Vec<T, 2>(x(0), (u(0) - p.K * x(1) / p.r) / p.R);
    }
  };
  using Measurements = std::tuple<EncoderCurrent>;
};

// The input of step k: a wobbling voltage and load (zero-input models: 0).
template <class Model>
InputOf<Model> StepInput(int k) {
  const double u[2] = {1.0 + std::sin(0.13 * k), 0.5 * std::cos(0.07 * k)};
  return InputFrom<Model>(u);
}

template <class Model>
Vec<double, Model::kStateDim> StartState() {
  Vec<double, Model::kStateDim> x = Vec<double, Model::kStateDim>::Zero();
  x(0) = 0.7;
  if (Model::kStateDim > 2) x(2) = 0.5;
  return x;
}

// An RK4 truth and its measurements with a deterministic wobble, computed
// before counting starts. gaps: the last component missing (NaN) in two of
// every three steps, a slower sensor (the subset update, issue 35).
template <class Model, class Meas>
std::vector<Vec<double, Meas::kDim>> Measurements(const typename Model::Params& params, bool gaps) {
  TransitionOptions topt;
  topt.integrator = Integrator::kRk4;
  auto truth = MakeTransition<Model>(params, topt);
  Vec<double, Model::kStateDim> x = StartState<Model>();
  std::vector<Vec<double, Meas::kDim>> z;
  z.reserve(kSteps);
  for (int k = 0; k < kSteps; ++k) {
    truth->SetInput(StepInput<Model>(k));
    x = truth->Step(x, k * kDt, (k + 1) * kDt);
    Vec<double, Meas::kDim> zk =
        EvalMeasurement<Model, Meas, double>((k + 1) * kDt, x, StepInput<Model>(k + 1), params);
    for (int j = 0; j < Meas::kDim; ++j) zk(j) += 0.01 * std::sin(0.37 * k + j);
    if (gaps && k % 3 != 0) zk(Meas::kDim - 1) = std::numeric_limits<double>::quiet_NaN();
    z.push_back(zk);
  }
  return z;
}

// Reads the whole result where the compiler cannot see it (so a heap
// allocation made for it, e.g. a dynamic gain, cannot be optimised away).
template <int M>
[[gnu::noinline]] double Consume(const StepResult<M>& r) {
  double s = r.log_likelihood + r.nis + r.innovation.sum() + r.residual.sum();
  for (Eigen::Index i = 0; i < r.gain.size(); ++i) s += r.gain.data()[i];
  return s + double(r.gain.rows()) + double(r.message.size());
}

// Heap allocations inside kSteps Predict + Update calls of `filter`.
template <class Model, class Meas>
long AllocationsInSteps(Filter<Model, Meas>& filter, const typename Model::Params& params,
                        bool gaps, std::string* failure) {
  constexpr int N = Model::kStateDim, M = Meas::kDim;
  const std::vector<Vec<double, M>> z = Measurements<Model, Meas>(params, gaps);
  const Mat<N, N> Q = 1e-4 * Mat<N, N>::Identity();
  const Mat<M, M> R = 1e-2 * Mat<M, M>::Identity();
  filter.Initialize(StartState<Model>(), 0.01 * Mat<N, N>::Identity());
  int failed_step = -1;
  double log_likelihood = 0.0;
  volatile double consumed = 0.0;
  AllocationCounter counter;
  for (int k = 0; k < kSteps; ++k) {
    // The line from u_k to u_k+1 (linear hold): the held input is its
    // special case, and a model without input holds 0.
    filter.SetInputPath(StepInput<Model>(k), StepInput<Model>(k + 1));
    const FilterStatus status = filter.Predict(k * kDt, (k + 1) * kDt, Q);
    filter.SetInput(StepInput<Model>(k + 1));  // seen by h(x, u)
    const StepResult<M> r = filter.Update(z[k], R);
    if ((status != FilterStatus::kOk || r.status != FilterStatus::kOk) && failed_step < 0)
      failed_step = k;
    log_likelihood += r.log_likelihood;
    consumed = consumed + Consume(r);
  }
  const long allocations = counter.Stop();
  if (failed_step >= 0)
    *failure = "step " + std::to_string(failed_step) + " failed: " + filter.last_error();
  else if (!std::isfinite(log_likelihood))
    *failure = "log-likelihood is not finite";
  return allocations;
}

template <class Model>
std::unique_ptr<Transition<Model>> Rk4(const typename Model::Params& params) {
  TransitionOptions topt;
  topt.integrator = Integrator::kRk4;
  return MakeTransition<Model>(params, topt);
}

template <class Model, class Meas>
void ExpectNoAllocations(Filter<Model, Meas>& filter, const typename Model::Params& params,
                         bool gaps = false) {
  std::string failure;
  const long allocations = AllocationsInSteps(filter, params, gaps, &failure);
  EXPECT_TRUE(failure.empty()) << filter.Name() << ": " << failure;
  EXPECT_EQ(allocations, 0) << filter.Name() << " allocated " << allocations << " times in "
                            << kSteps << " predict + update steps";
}

template <class Model, class Meas>
void CheckGaussianFilters(bool gaps = false) {
  const typename Model::Params params{};
  {
    KfOptions o;
    o.operating_point.assign(Model::kStateDim, 0.0);
    LinearizedKf<Model, Meas> kf(params, o);
    ExpectNoAllocations(kf, params, gaps);
  }
  {
    auto transition = Rk4<Model>(params);
    Ekf<Model, Meas> ekf(transition.get(), params, EkfOptions{});
    ExpectNoAllocations(ekf, params, gaps);
  }
  {
    auto transition = Rk4<Model>(params);
    EkfOptions o;
    o.iterations = 3;
    Ekf<Model, Meas> iekf(transition.get(), params, o);
    ExpectNoAllocations(iekf, params, gaps);
  }
  for (SigmaRule rule : {SigmaRule::kUnscented, SigmaRule::kCubature, SigmaRule::kGaussHermite}) {
    for (auto update :
         {SigmaPointOptions::Update::kRedraw, SigmaPointOptions::Update::kPropagate}) {
      auto transition = Rk4<Model>(params);
      SigmaPointOptions o;
      o.rule = rule;
      o.alpha = 0.5;
      o.gh_order = 3;
      o.update = update;
      SigmaPointFilter<Model, Meas> filter(transition.get(), params, o);
      SCOPED_TRACE(std::string(SigmaRuleName(rule)) +
                   (update == SigmaPointOptions::Update::kRedraw ? " redraw" : " propagate"));
      ExpectNoAllocations(filter, params, gaps);
    }
  }
}

TEST(AllocationFree, GaussianFiltersPendulumRk4) {
  CheckGaussianFilters<Pendulum, Pendulum::Sin>();
}

TEST(AllocationFree, GaussianFiltersDoublePendulumRk4) {
  CheckGaussianFilters<DoublePendulum, DoublePendulum::Angles>();
}

// Two inputs and a measurement that sees one (issue 34, done-when 5).
TEST(AllocationFree, GaussianFiltersTwoInputsAndHxuRk4) {
  CheckGaussianFilters<DcCart, DcCart::EncoderCurrent>();
}

// The particle filter keeps its particles in storage allocated once; with
// systematic resampling its steps do not allocate either.
TEST(AllocationFree, ParticleFilterSystematicPendulumRk4) {
  const Pendulum::Params params{};
  auto transition = Rk4<Pendulum>(params);
  ParticleOptions o;
  o.num_particles = 200;
  o.resample = ResampleScheme::kSystematic;
  o.ess_threshold = 1.0;
  ParticleFilter<Pendulum, Pendulum::Sin> pf(transition.get(), params, o);
  ExpectNoAllocations(pf, params);
}

// A slower sensor's gaps: the subset updates allocate nothing either.
TEST(AllocationFree, GaussianFiltersWithAComponentMissingDoublePendulumRk4) {
  CheckGaussianFilters<DoublePendulum, DoublePendulum::Angles>(true);
}

TEST(AllocationFree, ParticleFilterWithAComponentMissingDoublePendulumRk4) {
  const DoublePendulum::Params params{};
  auto transition = Rk4<DoublePendulum>(params);
  ParticleOptions o;
  o.num_particles = 200;
  o.resample = ResampleScheme::kSystematic;
  o.ess_threshold = 1.0;
  ParticleFilter<DoublePendulum, DoublePendulum::Angles> pf(transition.get(), params, o);
  ExpectNoAllocations(pf, params, true);
}

// Kept in a volatile global so the compiler cannot elide the allocation.
std::vector<double>* volatile g_sink = nullptr;

// The counter itself: an allocation inside the window is seen.
TEST(AllocationFree, CounterSeesAnAllocation) {
  AllocationCounter counter;
  g_sink = new std::vector<double>(16, 1.0);
  const long allocations = counter.Stop();
  EXPECT_GE(allocations, 2);  // the vector object and its buffer
  delete g_sink;
  g_sink = nullptr;
}

}  // namespace
}  // namespace estlab
