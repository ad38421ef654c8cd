// Generated model headers: the text of a small model's header, then real
// compiler checks through std::system: every example's header compiles for
// double, ceres::Jet and NestedJet (and the continuous ones satisfy the
// DynamicModel contract), and the generated pendulum and double pendulum give
// bit-identical results to the built-in models/pendulum.h and
// models/double_pendulum.h.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "src/modelfile/codegen.h"
#include "src/modelfile/cpp_names.h"
#include "src/modelfile/diagnostic.h"
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
// x_theta are both XThetaMeasurement; params is ParamsMeasurement).
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
      "static constexpr int kInputDim = 1;",
      "static constexpr bool kStiff = false;",
      "static constexpr bool kDiscreteTime = false;",
      "static constexpr std::array<const char*, 2> kStateNames = {\"x\", \"v\"};",
      "static constexpr std::array<const char*, 2> kStateUnits = {\"m\", \"m/s\"};",
      "static constexpr std::array<bool, 2> kAngleStates = {false, false};",
      "static constexpr std::array<std::pair<int, int>, 1> kPositionRatePairs = {{{0, 1}}};",
      "    S v_k = S(2.0);\n    S v_int = S(0.5);\n",
      "{\"k\", &Params::v_k, \"k [1/s]\", Constraint::kPositive},",
      "{\"int\", &Params::v_int, \"int\", Constraint::kAny},",
      "static Vec<T, 2> Rhs(const T& /*t*/, const Vec<T, 2>& x, double u, const P& p) {",
      "    using std::atan2;\n    using std::pow;\n    using std::sin;\n"
      "    const T& v_x = x(0);\n    const T& v_v = x(1);\n"
      "    const auto v_a11 = p.v_k + p.v_int;\n    const T v_s = sin(v_x);\n",
      "dx(0) = v_v;",
      "dx(1) = -p.v_k * (v_x * v_x) + model_fn::Square(v_x + 1.0) - pow(v_v, 2.5) + "
      "model_fn::PowT(T(p.v_k), v_v) + model_fn::Asin(v_s) + atan2(v_v, T(1.0)) + "
      "model_fn::Min(v_v, T(p.v_k)) + u * v_a11 + (v_v * v_v * v_v);",
      "static constexpr std::array<const char*, 1> kInvariantNames = {\"e\"};",
      "static bool InvariantsHold(const Params& p, double u) { return p.v_k == 0.0 && u == 0.0; }",
      "static Vec<double, 1> Invariants(const Vec<double, 2>& x, const Params& p) {\n"
      "    const double v_x = x(0);\n    const double v_v = x(1);\n",
      "inv(0) = (v_v * v_v) + p.v_k * (v_x * v_x);",
      "struct XThetaMeasurement {",
      "struct XThetaMeasurement2 {\n    static constexpr const char* kName = \"x_theta\";",
      "static constexpr std::array<bool, 1> kAngleOutputs = {true};",
      "static Vec<T, 1> Eval(const Vec<T, 2>& /*x*/, const P& p) {",
      "z(0) = T(p.v_k);",
      "struct ParamsMeasurement {",
      "z(0) = -(-v_v);",
      "using Measurements = std::tuple<XThetaMeasurement, XThetaMeasurement2, ParamsMeasurement>;",
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
                   "    const T& v_theta = x(0);\n"
                   "    const T& v_omega = x(1);\n"
                   "    Vec<T, 2> dx;\n"
                   "    dx(0) = v_omega;\n"
                   "    dx(1) = -(p.v_g / p.v_L) * sin(v_theta) - p.v_b * v_omega;\n"
                   "    return dx;\n"
                   "  }\n"),
            std::string::npos)
      << h;
  EXPECT_NE(h.find("return p.v_b == 0.0;"), std::string::npos);
}

TEST(Codegen, StepModelsHaveStepAndNoRhs) {
  const std::string h = HeaderOfExample("linear_cv.model", "LinearCv");
  EXPECT_NE(h.find("static constexpr bool kDiscreteTime = true;"), std::string::npos);
  EXPECT_NE(h.find("static Vec<T, 2> Step(const T& /*t*/, const Vec<T, 2>& x, double dt, "
                   "double /*u*/, const P& /*p*/) {"),
            std::string::npos)
      << h;
  EXPECT_NE(h.find("next(0) = v_pos + dt * v_vel;"), std::string::npos);
  EXPECT_NE(h.find("kPositionRatePairs = {{{0, 1}}};"), std::string::npos);  // pos + dt * vel
  EXPECT_EQ(h.find("Rhs("), std::string::npos);
  // No invariants: InvariantsHold is false, as in models/van_der_pol.h.
  EXPECT_NE(h.find("{ return false; }"), std::string::npos);
  EXPECT_NE(h.find("kParams = {};"), std::string::npos);
}

TEST(Codegen, MultiarmPairsAndTypeNames) {
  const std::string h = HeaderOfExample("multiarm_double_pendulum.model", "MultiarmDouble");
  EXPECT_NE(h.find("kPositionRatePairs = {{{0, 2}, {1, 3}}};"), std::string::npos);
  EXPECT_NE(h.find("const auto v_M11 = "), std::string::npos);  // params only: their scalar
  EXPECT_NE(h.find("const T v_M12 = v_coupling * cos(v_phi1 - v_phi2);"), std::string::npos);
  const ModelFile m = ParseModelFile(ReadFile(kSourceDir + "/examples/models/linear_cv.model"), "");
  EXPECT_EQ(DefaultTypeName(m), "LinearCvModel");
  EXPECT_THROW(GenerateModelHeader(m, "int"), InputError);
  EXPECT_THROW(GenerateModelHeader(m, "2x"), InputError);
  EXPECT_THROW(GenerateModelHeader(m, "NULL"), InputError);
  EXPECT_THROW(GenerateModelHeader(m, "Rhs"), InputError);  // the struct would hold Rhs()
  EXPECT_THROW(GenerateModelHeader(m, "AngleMeasurement"), InputError);
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
  EXPECT_EQ(LocalName("theta"), "v_theta");
  EXPECT_EQ(LocalName("x"), "v_x");
  EXPECT_EQ(LocalName("NDEBUG"), "v_NDEBUG");
  EXPECT_EQ(MemberName("class"), "v_class");
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

// Instantiates a generated model M for double, Jet and NestedJet (with
// double parameters and with parameters of the state's scalar): All<M>().
const char* const kInstantiateHelpers = R"(
#include <ceres/jet.h>
#include <tuple>

#include "models/model.h"
#include "models/model_params.h"
#include "src/ode/nested_jet.h"

namespace estlab::user_models {}  // the headers come after
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
  std::apply(
      [&](auto... meas) {
        ((void)estlab::EvalMeasurement<M, decltype(meas), T>(0.0, x, 0.0, p), ...);
      },
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

)";

const std::string kInstantiateAll = std::string(kInstantiateHelpers) + R"(
#include "pendulum.model.h"
#include "double_pendulum.model.h"
#include "multiarm_single_pendulum.model.h"
#include "multiarm_double_pendulum.model.h"
#include "linear_cv.model.h"

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

// A measurement that uses the time: h(t, x, u) (issue 34).
const char* const kTimeSensor = R"([model]
name = time-sensor
input = F
[states]
x = [m]
v = [m/s]
[params]
d = 0.05
w = 0.7
[rhs]
x = v
v = -x + F
[measurement drift]
pos = x + d * t
[measurement tach]
tach = v * cos(w * t) + 0.5 * F
[measurement plain]
x = x
)";

TEST(Codegen, MeasurementsThatUseTheTimeTakeIt) {
  const std::string h = GenerateModelHeader(ParseModelFile(kTimeSensor, "t.model"), "TimeSensor");
  const char* const expected[] = {
      "static Vec<T, 1> Eval(const T& t, const Vec<T, 2>& x, double /*u*/, const P& p) {",
      "z(0) = v_x + p.v_d * t;",
      "static Vec<T, 1> Eval(const T& t, const Vec<T, 2>& x, double u, const P& p) {",
      "static Vec<T, 1> Eval(const Vec<T, 2>& x, const P& /*p*/) {",
  };
  for (const char* e : expected) EXPECT_NE(h.find(e), std::string::npos) << e << "\nin:\n" << h;
}

TEST(Codegen, SensorGroupsBecomeTheMeasurementsGroups) {
  const char* const text =
      "[model]\nname = cart\n[states]\np = [m]\nv = [m/s]\n[rhs]\np = v\nv = -v\n"
      "[measurement nav: imu]\nspeed = v\n[measurement nav: gps]\npos = p\n";
  const std::string h = GenerateModelHeader(ParseModelFile(text, "cart.model"), "Cart");
  EXPECT_NE(h.find("static constexpr std::array<const char*, 2> kOutputs = {\"speed\", \"pos\"};\n"
                   "    static constexpr std::array<bool, 2> kAngleOutputs = {false, false};\n"
                   "    static constexpr std::array<OutputGroupSpec, 2> kGroups = "
                   "{{{\"imu\", 0, 1}, {\"gps\", 1, 1}}};"),
            std::string::npos)
      << h;
  EXPECT_NE(h.find("using Measurements = std::tuple<NavMeasurement>;"), std::string::npos);
}

// The generated h(t, x, u) compiles for every scalar, satisfies the
// contract, and EvalMeasurement passes it the time: at t = 2 the drift is
// x + 2 d and the tachometer v cos(2 w) + F / 2.
TEST_F(CompiledHeaders, TimeMeasurementCompilesAndSeesTheTime) {
  WriteFile(dir_ / "time_sensor.model.h",
            GenerateModelHeader(ParseModelFile(kTimeSensor, "t.model"), "TimeSensor"));
  const std::string program = std::string(kInstantiateHelpers) + R"(
#include <cmath>
#include <cstdio>
#include "time_sensor.model.h"

using M = um::TimeSensor;
static_assert(estlab::DynamicModel<M> && estlab::kAllMeasurementsOf<M>);
static_assert(estlab::MeasurementSeesTime<M::DriftMeasurement, M>);
static_assert(estlab::MeasurementSeesTime<M::TachMeasurement, M>);
static_assert(!estlab::MeasurementSeesTime<M::PlainMeasurement, M>);

int main() {
  All<M>();
  const M::Params p;
  const estlab::Vec<double, 2> x(0.3, -1.1);
  const double drift = estlab::EvalMeasurement<M, M::DriftMeasurement, double>(2.0, x, 0.4, p)(0);
  const double tach = estlab::EvalMeasurement<M, M::TachMeasurement, double>(2.0, x, 0.4, p)(0);
  const double want_drift = 0.3 + 2.0 * 0.05, want_tach = -1.1 * std::cos(1.4) + 0.2;
  if (std::abs(drift - want_drift) > 1e-15 || std::abs(tach - want_tach) > 1e-15) {
    std::printf("drift %.17g (want %.17g), tach %.17g (want %.17g)\n", drift, want_drift, tach,
                want_tach);
    return 1;
  }
}
)";
  std::string log;
  EXPECT_TRUE(Build(program, true, &log)) << log;
}

// ---- Every name `model check` accepts compiles (issue 40, done-when 3) ----

// The macros defined by the headers a model is compiled with (as the plugin
// compiles it: -DNDEBUG), from `g++ -dM -E`.
std::vector<std::string> PreambleMacros(const std::filesystem::path& dir) {
  WriteFile(dir / "preamble.cpp", std::string(kInstantiateHelpers) +
                                      "#include \"src/modelfile/model_functions.h\"\n"
                                      "#include \"src/core/params.h\"\n#include <array>\n"
                                      "#include <cmath>\n#include <utility>\n");
  const std::string out = (dir / "macros.txt").string();
  const std::string command = "g++ -std=c++20 -dM -E -DNDEBUG -I" + kSourceDir +
                              " -isystem /usr/include/eigen3 -DEIGEN_MPL2_ONLY " +
                              (dir / "preamble.cpp").string() + " > " + out + " 2>&1";
  EXPECT_EQ(std::system(command.c_str()), 0) << ReadFile(out);
  std::vector<std::string> names;
  std::istringstream lines(ReadFile(out));
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("#define ", 0) != 0) continue;
    const std::string name = line.substr(8, line.find_first_of(" (", 8) - 8);
    names.push_back(name);
  }
  return names;
}

constexpr int kModelNameLine = -2, kMeasurementLine = -3, kOutputLine = -4;

// One declared name of a generated model file and the line it is on.
struct Decl {
  enum Kind { kState, kParam, kLet, kInput } kind;
  std::string name;
};

// A model file of `decls` (states get -x dynamics, lets chain through the
// parameters, the first state's rhs uses the last let and the input) and,
// per line, the index of the declaration it belongs to (-1: none).
std::string ModelText(const std::string& model_name, const std::vector<Decl>& decls,
                      const std::string& meas, const std::string& output, std::vector<int>* owner) {
  std::vector<std::string> lines;
  auto add = [&](const std::string& line, int who) {
    lines.push_back(line);
    owner->push_back(who);
  };
  owner->clear();
  std::vector<int> states, params, lets;
  int input = -1;
  for (int i = 0; i < int(decls.size()); ++i) {
    if (decls[i].kind == Decl::kState) states.push_back(i);
    if (decls[i].kind == Decl::kParam) params.push_back(i);
    if (decls[i].kind == Decl::kLet) lets.push_back(i);
    if (decls[i].kind == Decl::kInput) input = i;
  }
  add("[model]", -1);
  add("name = " + model_name, kModelNameLine);
  if (input >= 0) add("input = " + decls[size_t(input)].name, input);
  add("[states]", -1);
  for (int i : states) add(decls[size_t(i)].name + " = [m]", i);
  add("[params]", -1);
  for (int i : params) add(decls[size_t(i)].name + " = 0.5", i);
  add("[let]", -1);
  std::string previous = decls[size_t(states[0])].name;
  for (size_t k = 0; k < lets.size(); ++k) {
    const std::string p = params.empty() ? "1" : decls[size_t(params[k % params.size()])].name;
    add(decls[size_t(lets[k])].name + " = " + previous + " + " + p, lets[k]);
    previous = decls[size_t(lets[k])].name;
  }
  add("[rhs]", -1);
  for (size_t k = 0; k < states.size(); ++k) {
    const std::string& x = decls[size_t(states[k])].name;
    std::string rhs = "-" + x;
    if (k == 0) rhs += " + 1e-9 * " + previous;
    if (k == 0 && input >= 0) rhs += " + " + decls[size_t(input)].name;
    add(x + " = " + rhs, states[k]);
  }
  add("[measurement " + meas + "]", kMeasurementLine);
  add(output + " = " + decls[size_t(states[0])].name, kOutputLine);
  std::string text;
  for (const std::string& line : lines) text += line + "\n";
  return text;
}

// The model of `decls` once `model check` accepts it: every refusal must
// name t.model:LINE:COL; the declaration on that line goes (or the model,
// measurement or output name is replaced), and the file is checked again.
ModelFile Accepted(std::vector<Decl>* decls, std::string* model_name, std::string* meas,
                   std::string* output) {
  for (int round = 0; round < 40; ++round) {
    std::vector<int> owner;
    const std::string text = ModelText(*model_name, *decls, *meas, *output, &owner);
    try {
      return ParseModelFile(text, "t.model");
    } catch (const ModelFileError& e) {
      std::set<int> drop;
      std::istringstream lines(e.what());
      for (std::string line; std::getline(lines, line);) {
        int at = 0, col = 0;
        EXPECT_EQ(std::sscanf(line.c_str(), "t.model:%d:%d: ", &at, &col), 2) << line;
        if (!(at >= 1 && at <= int(owner.size()) && col >= 1)) {
          ADD_FAILURE() << "no FILE:LINE:COL: " << line;
          return {};
        }
        const int who = owner[size_t(at - 1)];
        const std::string fresh = std::to_string(round);
        drop.insert(who);
        if (who == kModelNameLine) *model_name = "m" + fresh;
        if (who == kMeasurementLine) *meas = "meas" + fresh;
        if (who == kOutputLine) *output = "out" + fresh;
      }
      for (auto it = drop.rbegin(); it != drop.rend() && *it >= 0; ++it) {
        const bool last_state = (*decls)[size_t(*it)].kind == Decl::kState &&
                                std::count_if(decls->begin(), decls->end(), [](const Decl& d) {
                                  return d.kind == Decl::kState;
                                }) == 1;
        if (last_state)
          (*decls)[size_t(*it)].name = "s" + std::to_string(round);
        else
          decls->erase(decls->begin() + *it);
      }
    }
  }
  ADD_FAILURE() << "not accepted after 40 rounds";
  return {};
}

TEST_F(CompiledHeaders, EveryNameCheckAcceptsCompiles) {
  const std::vector<std::string> macros = PreambleMacros(dir_);
  ASSERT_GT(macros.size(), 500u);
  // The spellings the generated C++ adds to a user's names start or end with
  // text no macro does.
  for (const std::string& m : macros) {
    EXPECT_NE(m.rfind(kValuePrefix, 0), 0u) << m;
    for (const std::string tail : {"Model", "Measurement"})
      EXPECT_FALSE(m.size() >= tail.size() &&
                   m.compare(m.size() - tail.size(), tail.size(), tail) == 0)
          << m;
  }
  std::vector<std::string> pool = {
      // keywords
      "int", "class", "double", "return", "template", "typename", "using", "namespace", "auto",
      "const", "static", "struct", "new", "delete", "this", "true", "false", "operator", "and",
      "or", "not", "bool", "char", "long", "void", "volatile", "virtual", "concept", "requires",
      "co_await", "import", "module", "final", "override", "asm", "register", "typeid",
      // the generator's own names and estlab's
      "T", "P", "S", "x", "u", "p", "z", "dx", "next", "inv", "std", "estlab", "ceres", "Eigen",
      "Vec", "Params", "ParamsT", "ParamSpec", "Constraint", "Measurements", "Rhs", "Step", "Eval",
      "Invariants", "InvariantsHold", "model_fn", "user_models", "kName", "kParams", "kStateDim",
      "kDim", "kOutputs", "Mat", "Jet", "NestedJet", "Model", "params", "vec", "constraint", "rhs",
      "measurements", "params_t", "param_spec",
      // reserved by the language (check refuses them: FILE:LINE:COL)
      "t", "dt", "pi", "sin", "exp", "max", "a__b", "w_"};
  for (const std::string& m : macros)
    if (!m.empty() && m.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz"
                                          "0123456789_") == std::string::npos)
      pool.push_back(m);
  std::sort(pool.begin(), pool.end());
  pool.erase(std::unique(pool.begin(), pool.end()), pool.end());

  // Every name of the pool once, in models of up to 16 states and 16
  // parameters (more and the parameters-of-T path tune compiles would be
  // skipped) and 100 lets, six models per compile.
  std::mt19937 rng(1);
  std::shuffle(pool.begin(), pool.end(), rng);
  size_t next = 0;
  auto take = [&] { return pool[next++ % pool.size()]; };
  std::set<std::string> types;
  for (int program = 0; next < pool.size(); ++program) {
    std::string includes, calls;
    for (int k = 0; k < 6 && next < pool.size(); ++k) {
      const int n = int(types.size());
      const int states = 1 + int(rng() % kMaxStates);
      std::vector<Decl> decls;
      for (int i = 0; i < states; ++i) decls.push_back({Decl::kState, take()});
      decls.push_back({Decl::kInput, take()});
      for (int i = 0; i < 1 + int(rng() % 16); ++i) decls.push_back({Decl::kParam, take()});
      for (int i = 0; i < 100; ++i) decls.push_back({Decl::kLet, take()});
      std::string model_name = take(), meas = take(), output = take();
      if (n % 2 == 0) std::replace(meas.begin(), meas.end(), '_', '-');  // both spellings
      std::replace(model_name.begin(), model_name.end(), '_', '-');
      ModelFile m;
      ASSERT_NO_FATAL_FAILURE(m = Accepted(&decls, &model_name, &meas, &output));
      if (types.count(DefaultTypeName(m))) {  // two names of one CamelCase
        model_name = "model-" + std::to_string(n);
        ASSERT_NO_FATAL_FAILURE(m = Accepted(&decls, &model_name, &meas, &output));
      }
      const std::string type = DefaultTypeName(m);
      types.insert(type);
      const std::string header = "prop" + std::to_string(n) + ".h";
      WriteFile(dir_ / header, GenerateModelHeader(m, type));
      includes += "#include \"" + header + "\"\n";
      calls += "  All<um::" + type + ">();\n";
    }
    std::string log;
    EXPECT_TRUE(
        Build(std::string(kInstantiateHelpers) + includes + "int main() {\n" + calls + "}\n", false,
              &log))
        << "program " << program << ":\n"
        << includes << log.substr(0, 4000);
  }
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
