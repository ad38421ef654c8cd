// Generated model headers: the text of a small model's header, then real
// compiler checks through std::system: every example's header compiles for
// double, ceres::Jet and NestedJet (and the continuous ones satisfy the
// DynamicModel contract), and the generated pendulum and double pendulum give
// bit-identical results to the built-in models/pendulum.h and
// models/double_pendulum.h.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "src/modelfile/codegen.h"
#include "src/modelfile/cpp_names.h"
#include "src/modelfile/model_file.h"

#ifndef ESTLAB_SOURCE_DIR
#error "ESTLAB_SOURCE_DIR must be defined to the project root"
#endif

namespace estlab::modelfile {
namespace {

const std::string kSourceDir = ESTLAB_SOURCE_DIR;

std::string ReadFile(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

void WriteFile(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path) << text;
}

std::string HeaderOfExample(const std::string& file, const std::string& type) {
  const std::string path = "examples/models/" + file;
  return GenerateModelHeader(ParseModelFile(ReadFile(kSourceDir + "/" + path), path), type);
}

// A model using every code-generation case: a state named like the state
// vector (x), a parameter named like a keyword (int), double and T lets, an
// unused let, every kind of power, helper functions, mixed-type arguments,
// an input, measurement names whose structs would collide (x-theta and
// x_theta are both XTheta; Params is taken).
const char* const kFeatures = R"([model]
name = features
description = quote " and backslash \ here
input = F
[states]
x = [m]
v = [m/s]
[params]
k = 2 > 0 [1/s]
int = 0.5
[let]
a11 = k + int
unused = v * 3
s = sin(x)
[rhs]
x = v
v = -k * x^2 + (x + 1)^2 - pow(v, 2.5) + k^v + asin(s) + atan2(v, 1) + min(v, k) + F * a11 + v^3
[measurement x-theta]
x = x
[measurement x_theta]
k = k : angle
[measurement params]
v = -(-v)
[invariant energy]
e = v^2 + k * x^2
conserved-if-zero = k, F
)";

TEST(Codegen, HeaderHasTheBuiltInForm) {
  const std::string h = GenerateModelHeader(ParseModelFile(kFeatures, "f.model"), "Features");
  const char* const expected[] = {
      "#ifndef ESTLAB_USER_MODELS_FEATURES_H_",
      "#include \"src/modelfile/model_functions.h\"",
      "namespace estlab::user_models {",
      "struct Features {",
      "static constexpr const char* kName = \"features\";",
      "static constexpr const char* kDescription = \"quote \\\" and backslash \\\\ here\";",
      "static constexpr int kStateDim = 2;",
      "static constexpr bool kHasInput = true;",
      "static constexpr bool kStiff = false;",
      "static constexpr bool kDiscreteTime = false;",
      "static constexpr std::array<const char*, 2> kStateNames = {\"x\", \"v\"};",
      "static constexpr std::array<const char*, 2> kStateUnits = {\"m\", \"m/s\"};",
      "static constexpr std::array<bool, 2> kAngleStates = {false, false};",
      "static constexpr std::array<std::pair<int, int>, 1> kPositionRatePairs = {{{0, 1}}};",
      "    S k = S(2.0);\n    S int_ = S(0.5);\n",
      "{\"k\", &Params::k, \"k [1/s]\", Constraint::kPositive},",
      "{\"int\", &Params::int_, \"int\", Constraint::kAny},",
      "static Vec<T, 2> Rhs(const T& /*t*/, const Vec<T, 2>& x, double u, const P& p) {",
      "    using std::atan2;\n    using std::pow;\n    using std::sin;\n"
      "    const T& x_ = x(0);\n    const T& v = x(1);\n"
      "    const auto a11 = p.k + p.int_;\n    const T s = sin(x_);\n",
      "dx(0) = v;",
      "dx(1) = -p.k * (x_ * x_) + model_fn::Square(x_ + 1.0) - pow(v, 2.5) + "
      "model_fn::PowT(T(p.k), v) + model_fn::Asin(s) + atan2(v, T(1.0)) + model_fn::Min(v, "
      "T(p.k)) + u * a11 + (v * v * v);",
      "static constexpr std::array<const char*, 1> kInvariantNames = {\"e\"};",
      "static bool InvariantsHold(const Params& p, double u) { return p.k == 0.0 && u == 0.0; }",
      "static Vec<double, 1> Invariants(const Vec<double, 2>& x, const Params& p) {\n"
      "    const double x_ = x(0);\n    const double v = x(1);\n",
      "inv(0) = (v * v) + p.k * (x_ * x_);",
      "struct XTheta {",
      "struct XThetaMeasurement {\n    static constexpr const char* kName = \"x_theta\";",
      "static constexpr std::array<bool, 1> kAngleOutputs = {true};",
      "static Vec<T, 1> Eval(const Vec<T, 2>& /*x*/, const P& p) {",
      "z(0) = T(p.k);",
      "struct ParamsMeasurement {",
      "z(0) = -(-v);",
      "using Measurements = std::tuple<XTheta, XThetaMeasurement, ParamsMeasurement>;",
      "}  // namespace estlab::user_models",
  };
  for (const char* e : expected) EXPECT_NE(h.find(e), std::string::npos) << e << "\nin:\n" << h;
  EXPECT_EQ(h.find("unused"), std::string::npos);  // lets no equation needs are left out
  EXPECT_EQ(h.find("static Vec<T, 2> Step("), std::string::npos);
}

TEST(Codegen, PendulumRhsIsTheBuiltInsExpression) {
  const std::string h = HeaderOfExample("pendulum.model", "PendulumFile");
  EXPECT_NE(h.find("  template <class T, class P>\n"
                   "  static Vec<T, 2> Rhs(const T& /*t*/, const Vec<T, 2>& x, double /*u*/, "
                   "const P& p) {\n"
                   "    using std::sin;\n"
                   "    const T& theta = x(0);\n"
                   "    const T& omega = x(1);\n"
                   "    Vec<T, 2> dx;\n"
                   "    dx(0) = omega;\n"
                   "    dx(1) = -(p.g / p.L) * sin(theta) - p.b * omega;\n"
                   "    return dx;\n"
                   "  }\n"),
            std::string::npos)
      << h;
  EXPECT_NE(h.find("return p.b == 0.0;"), std::string::npos);
}

TEST(Codegen, StepModelsHaveStepAndNoRhs) {
  const std::string h = HeaderOfExample("linear_cv.model", "LinearCv");
  EXPECT_NE(h.find("static constexpr bool kDiscreteTime = true;"), std::string::npos);
  EXPECT_NE(h.find("static Vec<T, 2> Step(const T& /*t*/, const Vec<T, 2>& x, double dt, "
                   "double /*u*/, const P& /*p*/) {"),
            std::string::npos)
      << h;
  EXPECT_NE(h.find("next(0) = pos + dt * vel;"), std::string::npos);
  EXPECT_NE(h.find("kPositionRatePairs = {{{0, 1}}};"), std::string::npos);  // pos + dt * vel
  EXPECT_EQ(h.find("Rhs("), std::string::npos);
  // No invariants: InvariantsHold is false, as in models/van_der_pol.h.
  EXPECT_NE(h.find("{ return false; }"), std::string::npos);
  EXPECT_NE(h.find("kParams = {};"), std::string::npos);
}

TEST(Codegen, MultiarmPairsAndTypeNames) {
  const std::string h = HeaderOfExample("multiarm_double_pendulum.model", "MultiarmDouble");
  EXPECT_NE(h.find("kPositionRatePairs = {{{0, 2}, {1, 3}}};"), std::string::npos);
  EXPECT_NE(h.find("const auto M11 = "), std::string::npos);  // params only: their scalar
  EXPECT_NE(h.find("const T M12 = coupling * cos(phi1 - phi2);"), std::string::npos);
  const ModelFile m = ParseModelFile(ReadFile(kSourceDir + "/examples/models/linear_cv.model"), "");
  EXPECT_EQ(DefaultTypeName(m), "LinearCv");
  EXPECT_THROW(GenerateModelHeader(m, "int"), InputError);
  EXPECT_THROW(GenerateModelHeader(m, "2x"), InputError);
  EXPECT_THROW(GenerateModelHeader(m, "NULL"), InputError);
}

TEST(Codegen, CppSpellings) {
  EXPECT_EQ(FormatDouble(2), "2.0");
  EXPECT_EQ(FormatDouble(0.1), "0.1");
  EXPECT_EQ(FormatDouble(9.81), "9.81");
  EXPECT_EQ(FormatDouble(1e300), "1e+300");
  EXPECT_EQ(FormatDouble(1.0 / 3.0), "0.3333333333333333");
  EXPECT_EQ(std::strtod(FormatDouble(0.15 * 0.17 * 0.17 / 12).c_str(), nullptr),
            0.15 * 0.17 * 0.17 / 12);
  EXPECT_EQ(CppStringLiteral("a\"b\\c\n\xc3\xa9"), "\"a\\\"b\\\\c\\012\\303\\251\"");
  EXPECT_EQ(LocalName("theta"), "theta");
  EXPECT_EQ(LocalName("x"), "x_");
  EXPECT_EQ(LocalName("T"), "T_");
  EXPECT_EQ(LocalName("M_PI"), "M_PI_");
  EXPECT_EQ(LocalName("EOF"), "EOF_");
  EXPECT_EQ(LocalName("M12"), "M12");
  EXPECT_EQ(MemberName("x"), "x");
  EXPECT_EQ(MemberName("class"), "class_");
  EXPECT_EQ(CamelCase("angle-rate"), "AngleRate");
  EXPECT_EQ(UpperSnakeCase("PendulumFile"), "PENDULUM_FILE");
}

// ---- Compiling the generated code ------------------------------------------

bool HaveCompiler() { return std::system("g++ --version > /dev/null 2>&1") == 0; }

// A fresh directory holding the generated headers of every example.
class CompiledHeaders : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!HaveCompiler()) GTEST_SKIP() << "g++ not found";
    char pattern[] = "/tmp/estlab_modelfile_XXXXXX";
    ASSERT_NE(mkdtemp(pattern), nullptr);
    dir_ = pattern;
    const std::pair<const char*, const char*> examples[] = {
        {"pendulum.model", "PendulumFile"},
        {"double_pendulum.model", "DoublePendulumFile"},
        {"multiarm_single_pendulum.model", "MultiarmSinglePendulum"},
        {"multiarm_double_pendulum.model", "MultiarmDoublePendulum"},
        {"linear_cv.model", "LinearCv"}};
    for (const auto& [file, type] : examples)
      WriteFile(dir_ / (std::string(file) + ".h"), HeaderOfExample(file, type));
  }
  void TearDown() override {
    if (!dir_.empty()) std::filesystem::remove_all(dir_);
  }

  // Compiles (and with `run`, links and runs) `program`; the log on failure.
  bool Build(const std::string& program, bool run, std::string* log) {
    WriteFile(dir_ / "program.cpp", program);
    const std::string flags = "-std=c++20 -Wall -Wextra -Werror -I" + kSourceDir + " -I" +
                              dir_.string() + " -isystem /usr/include/eigen3 -DEIGEN_MPL2_ONLY ";
    const std::string out = (dir_ / "log.txt").string();
    const std::string command = run ? "g++ -O0 " + flags + (dir_ / "program.cpp").string() +
                                          " -o " + (dir_ / "program").string() + " > " + out +
                                          " 2>&1 && " + (dir_ / "program").string() + " >> " + out +
                                          " 2>&1"
                                    : "g++ -fsyntax-only " + flags +
                                          (dir_ / "program.cpp").string() + " > " + out + " 2>&1";
    const int status = std::system(command.c_str());
    *log = ReadFile(out);
    return status == 0;
  }

  std::filesystem::path dir_;
};

const char* const kInstantiateAll = R"(
#include <ceres/jet.h>
#include <tuple>

#include "models/model.h"
#include "models/model_params.h"
#include "src/ode/nested_jet.h"
#include "pendulum.model.h"
#include "double_pendulum.model.h"
#include "multiarm_single_pendulum.model.h"
#include "multiarm_double_pendulum.model.h"
#include "linear_cv.model.h"

namespace um = estlab::user_models;

template <class M, class T, class P>
void InstantiateWith(const P& p) {
  const estlab::Vec<T, M::kStateDim> x = estlab::Vec<T, M::kStateDim>::Constant(T(0.25));
  if constexpr (M::kDiscreteTime) {
    const estlab::Vec<T, M::kStateDim> y = M::template Step<T>(T(0.0), x, 0.01, 0.0, p);
    (void)y;
  } else {
    const estlab::Vec<T, M::kStateDim> y = M::template Rhs<T>(T(0.0), x, 0.0, p);
    (void)y;
  }
  std::apply([&](auto... meas) { ((void)decltype(meas)::template Eval<T>(x, p), ...); },
             typename M::Measurements{});
}

// With double parameters, and with parameters of the state's scalar (as
// `estlab tune --estimate-param` runs them).
template <class M, class T>
void Instantiate() {
  InstantiateWith<M, T>(typename M::Params{});
  if constexpr (estlab::EstimableParams<M>) {
    std::array<T, M::kParams.size()> v;
    v.fill(T(0.5));
    InstantiateWith<M, T>(estlab::MakeParams<M, T>(v));
  }
}

template <class M>
void All() {
  Instantiate<M, double>();
  Instantiate<M, ceres::Jet<double, 2>>();
  Instantiate<M, estlab::NestedJet<2, M::kStateDim>>();
  (void)M::Invariants(estlab::Vec<double, M::kStateDim>::Zero(), typename M::Params{});
  (void)M::InvariantsHold(typename M::Params{}, 0.0);
}

static_assert(estlab::DynamicModel<um::PendulumFile>);
static_assert(estlab::DynamicModel<um::DoublePendulumFile>);
static_assert(estlab::DynamicModel<um::MultiarmSinglePendulum>);
static_assert(estlab::DynamicModel<um::MultiarmDoublePendulum>);
static_assert(estlab::kAllMeasurementsOf<um::PendulumFile>);
static_assert(estlab::EstimableParams<um::PendulumFile>);
static_assert(estlab::EstimableParams<um::MultiarmSinglePendulum>);
static_assert(estlab::EstimableParams<um::MultiarmDoublePendulum>);
static_assert(estlab::kAllMeasurementsOf<um::MultiarmDoublePendulum>);
static_assert(um::LinearCv::kDiscreteTime && estlab::DynamicModel<um::LinearCv>);
static_assert(estlab::kDiscreteTime<um::LinearCv> && !estlab::kDiscreteTime<um::PendulumFile>);

int main() {
  All<um::PendulumFile>();
  All<um::DoublePendulumFile>();
  All<um::MultiarmSinglePendulum>();
  All<um::MultiarmDoublePendulum>();
  All<um::LinearCv>();
}
)";

TEST_F(CompiledHeaders, EveryExampleCompilesForDoubleJetAndNestedJet) {
  std::string log;
  EXPECT_TRUE(Build(kInstantiateAll, false, &log)) << log;
}

// Exits 0 when the generated models match the built-ins bit for bit: Rhs in
// double and ceres::Jet (values and derivatives) and NestedJet, Invariants,
// every measurement, and the tables.
const char* const kCompareWithBuiltIns = R"(
#include <ceres/jet.h>

#include <bit>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <tuple>
#include <vector>

#include "models/double_pendulum.h"
#include "models/pendulum.h"
#include "src/ode/nested_jet.h"
#include "pendulum.model.h"
#include "double_pendulum.model.h"

int failures = 0;

void Same(double a, double b, const char* what) {
  if (std::bit_cast<std::uint64_t>(a) != std::bit_cast<std::uint64_t>(b)) {
    std::printf("%s: %.17g != %.17g\n", what, a, b);
    ++failures;
  }
}
void SameText(const char* a, const char* b, const char* what) {
  if (std::strcmp(a, b) != 0) {
    std::printf("%s: '%s' != '%s'\n", what, a, b);
    ++failures;
  }
}

template <class B, class G>
typename G::Params Convert(const typename B::Params& pb) {
  typename G::Params pg;
  for (size_t k = 0; k < B::kParams.size(); ++k) {
    SameText(B::kParams[k].name, G::kParams[k].name, "parameter name");
    Same(double(B::kParams[k].constraint), double(G::kParams[k].constraint), "constraint");
    pg.*(G::kParams[k].member) = pb.*(B::kParams[k].member);
  }
  return pg;
}

template <class B, class G>
void CompareTables() {
  static_assert(B::kStateDim == G::kStateDim && B::kParams.size() == G::kParams.size());
  SameText(B::kDescription, G::kDescription, "description");
  for (int i = 0; i < B::kStateDim; ++i) {
    SameText(B::kStateNames[i], G::kStateNames[i], "state name");
    SameText(B::kStateUnits[i], G::kStateUnits[i], "state unit");
    Same(B::kAngleStates[i], G::kAngleStates[i], "angle state");
  }
  if (B::kPositionRatePairs != G::kPositionRatePairs) {
    std::printf("position-rate pairs differ\n");
    ++failures;
  }
  Same(B::kInvariantNames.size(), G::kInvariantNames.size(), "invariant count");
  const typename B::Params defaults;
  const typename G::Params converted = Convert<B, G>(defaults);
  const typename G::Params generated_defaults;
  for (size_t k = 0; k < B::kParams.size(); ++k)
    Same(converted.*(G::kParams[k].member), generated_defaults.*(G::kParams[k].member), "default");
}

template <class B, class G, size_t... I>
void CompareMeasurements(const estlab::Vec<double, B::kStateDim>& x, const typename B::Params& pb,
                         const typename G::Params& pg, std::index_sequence<I...>) {
  auto one = [&](auto mb, auto mg) {
    using MB = decltype(mb);
    using MG = decltype(mg);
    SameText(MB::kName, MG::kName, "measurement name");
    static_assert(MB::kDim == MG::kDim);
    const auto zb = MB::template Eval<double>(x, pb);
    const auto zg = MG::template Eval<double>(x, pg);
    for (int r = 0; r < MB::kDim; ++r) {
      SameText(MB::kOutputs[r], MG::kOutputs[r], "output name");
      Same(MB::kAngleOutputs[r], MG::kAngleOutputs[r], "angle output");
      Same(zb(r), zg(r), MB::kName);
    }
  };
  (one(std::tuple_element_t<I, typename B::Measurements>{},
       std::tuple_element_t<I, typename G::Measurements>{}),
   ...);
}

template <class B, class G>
void CompareAt(const estlab::Vec<double, B::kStateDim>& x, const typename B::Params& pb) {
  constexpr int N = B::kStateDim;
  const typename G::Params pg = Convert<B, G>(pb);
  const estlab::Vec<double, N> fb = B::template Rhs<double>(0.5, x, 0.0, pb);
  const estlab::Vec<double, N> fg = G::template Rhs<double>(0.5, x, 0.0, pg);
  for (int i = 0; i < N; ++i) Same(fb(i), fg(i), "Rhs<double>");

  using J = ceres::Jet<double, N>;
  estlab::Vec<J, N> xj;
  for (int i = 0; i < N; ++i) xj(i) = J(x(i), i);
  const estlab::Vec<J, N> jb = B::template Rhs<J>(J(0.5), xj, 0.0, pb);
  const estlab::Vec<J, N> jg = G::template Rhs<J>(J(0.5), xj, 0.0, pg);
  for (int i = 0; i < N; ++i) {
    Same(jb(i).a, jg(i).a, "Rhs<Jet> value");
    for (int c = 0; c < N; ++c) Same(jb(i).v(c), jg(i).v(c), "Rhs<Jet> derivative");
  }

  using NJ = estlab::NestedJet<2, N>;
  estlab::Vec<NJ, N> xn;
  for (int i = 0; i < N; ++i) xn(i) = NJ(x(i));
  const estlab::Vec<NJ, N> nb = B::template Rhs<NJ>(NJ(0.5), xn, 0.0, pb);
  const estlab::Vec<NJ, N> ng = G::template Rhs<NJ>(NJ(0.5), xn, 0.0, pg);
  for (int i = 0; i < N; ++i) Same(nb(i).scalar(), ng(i).scalar(), "Rhs<NestedJet>");

  const auto eb = B::Invariants(x, pb);
  const auto eg = G::Invariants(x, pg);
  for (int i = 0; i < eb.size(); ++i) Same(eb(i), eg(i), "Invariants");
  Same(B::InvariantsHold(pb, 0.0), G::InvariantsHold(pg, 0.0), "InvariantsHold");
  CompareMeasurements<B, G>(
      x, pb, pg, std::make_index_sequence<std::tuple_size_v<typename B::Measurements>>{});
}

int main() {
  using estlab::models::DoublePendulum;
  using estlab::models::Pendulum;
  namespace um = estlab::user_models;
  CompareTables<Pendulum, um::PendulumFile>();
  CompareTables<DoublePendulum, um::DoublePendulumFile>();
  Pendulum::Params damped{9.7, 0.8, 0.3};
  for (const Pendulum::Params& p : {Pendulum::Params{}, damped}) {
    for (const auto& s : std::vector<std::vector<double>>{
             {0.3, -1.2}, {3.0, 4.5}, {-2.5, 0.01}, {1e-8, -7.0}, {12.0, 0.0}})
      CompareAt<Pendulum, um::PendulumFile>(estlab::Vec<double, 2>(s[0], s[1]), p);
  }
  DoublePendulum::Params odd{9.81, 0.7, 1.3, 0.5, 2.0};
  for (const DoublePendulum::Params& p : {DoublePendulum::Params{}, odd}) {
    for (const auto& s : std::vector<std::vector<double>>{
             {0.3, -1.2, 2.0, 0.7}, {3.0, 4.5, -3.1, -6.0}, {-2.5, 0.01, 1e-7, 9.0}})
      CompareAt<DoublePendulum, um::DoublePendulumFile>(
          estlab::Vec<double, 4>(s[0], s[1], s[2], s[3]), p);
  }
  std::printf("%d differences\n", failures);
  return failures == 0 ? 0 : 1;
}
)";

TEST_F(CompiledHeaders, PendulumAndDoublePendulumAreBitIdenticalToTheBuiltIns) {
  std::string log;
  EXPECT_TRUE(Build(kCompareWithBuiltIns, true, &log)) << log;
  EXPECT_NE(log.find("0 differences"), std::string::npos) << log;
}

}  // namespace
}  // namespace estlab::modelfile
