// `estlab model source FILE --out DIR [--tuner]` and the registration of
// linked models (what estlab_add_model builds on): the files written are the
// generator's text (src/registry/model_source.h), the linked entry differs
// from the run-time plugin's only in its last lines, a linked model is found
// by name, and bad input exits 2 writing nothing.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "cli/cli_test_util.h"
#include "src/core/types.h"
#include "src/modelfile/codegen.h"
#include "src/modelfile/model_file.h"
#include "src/registry/linked_models.h"
#include "src/registry/model_source.h"
#include "src/registry/registry.h"

namespace estlab::testing {
namespace {

namespace fs = std::filesystem;

std::string Source(const std::string& rel) { return std::string(ESTLAB_SOURCE_DIR) + "/" + rel; }

TEST(ModelSource, ModelFileWritesTheGeneratedHeaderEntryAndTuner) {
  TempDir dir;
  const std::string file = Source("examples/models/pendulum.model");
  const RunResult r = RunEstlab("model source '" + file + "' --out gen --tuner", dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, "model pendulum-file: wrote gen/model.h, entry.cpp, tune.cpp\n");
  const modelfile::ModelFile m = modelfile::ParseModelFile(ReadFile(file), file);
  EXPECT_EQ(ReadFile(dir.File("gen/model.h")),
            modelfile::GenerateModelHeader(m, "PendulumFileModel"));
  const std::string entry = ReadFile(dir.File("gen/entry.cpp"));
  EXPECT_NE(entry.find("#include \"model.h\"\n"), std::string::npos) << entry;
  EXPECT_NE(entry.find("#define ESTLAB_MODEL_TYPE estlab::user_models::PendulumFileModel\n"),
            std::string::npos);
  EXPECT_NE(entry.find("ESTLAB_DEFINE_LINKED_MODEL(ESTLAB_MODEL_TYPE, true)\n"), std::string::npos);
  EXPECT_NE(ReadFile(dir.File("gen/tune.cpp"))
                .find("template estlab::TuneResult estlab::TuneModel<ESTLAB_MODEL_TYPE>("),
            std::string::npos);
}

TEST(ModelSource, LinkedAndPluginEntriesShareAllButTheRegistration) {
  const ModelSource s = ReadModelSource(Source("examples/models/double_pendulum.model"));
  const std::string linked = ModelEntryUnit(s, "model.h", ModelLinkage::kLinked, false);
  const std::string plugin = ModelEntryUnit(s, "model.h", ModelLinkage::kPlugin, false);
  const std::string head =
      linked.substr(0, linked.find("#include \"src/registry/linked_models.h\""));
  EXPECT_EQ(plugin.substr(0, head.size()), head);
  EXPECT_NE(head.find("#include \"src/registry/model_entry_impl.h\""), std::string::npos);
  EXPECT_NE(plugin.find("ESTLAB_DEFINE_MODEL_PLUGIN(ESTLAB_MODEL_TYPE)"), std::string::npos);
  EXPECT_EQ(linked.substr(head.size()),
            "#include \"src/registry/linked_models.h\"\n"
            "ESTLAB_DEFINE_LINKED_MODEL(ESTLAB_MODEL_TYPE, false)\n");
}

// Issue 38: a command's parts unit (src/run/run_parts.h) spells out its
// parts, names its library after them, and lets only a C identifier into
// the code: a --measure of sensor groups, or anything else, compiles every
// measurement and appears nowhere in the unit.
TEST(ModelSource, PartsUnitNamesItsPartsAndOnlyAnIdentifierEntersTheCode) {
  const ModelSource s = ReadModelSource(Source("examples/models/pendulum.model"));
  const RunNeeds ukf{.measurement = "sin", .filter = 2, .adapt = true, .smooth = false};
  EXPECT_EQ(PartsLibraryName(ukf), "run-sin-sigma-adapt");
  const std::string unit = ModelPartsUnit(s, "model.h", ukf);
  for (const char* line :
       {"#include \"model.h\"\n", "#include \"src/registry/model_entry_impl.h\"\n",
        "  static constexpr const char* kMeasurement = \"sin\";\n",
        "  static constexpr int kFilter = 2;\n",
        "  static constexpr bool kAdapt = true, kSmooth = false, kSimulate = false;\n",
        "ESTLAB_DEFINE_MODEL_PARTS_PLUGIN(ESTLAB_MODEL_TYPE, EstlabRunParts)\n"})
    EXPECT_NE(unit.find(line), std::string::npos) << line << "\n" << unit;
  EXPECT_EQ(PartsLibraryName(RunNeeds{.filter = -2, .simulate = true}), "run-all-none-sim");
  EXPECT_EQ(PartsLibraryName(RunNeeds{.measurement = "full", .smooth = true}),
            "run-full-all-smooth");
  for (const std::string odd : {"imu,gps", "sin\"; int x; //", "2sin", "s in", ""}) {
    const RunNeeds needs{.measurement = odd, .filter = 0};
    EXPECT_EQ(PartsLibraryName(needs), "run-all-kf") << odd;
    const std::string text = ModelPartsUnit(s, "model.h", needs);
    EXPECT_NE(text.find("kMeasurement = nullptr;"), std::string::npos) << odd;
    if (!odd.empty()) {
      EXPECT_EQ(text.find(odd), std::string::npos) << odd;
    }
  }
  // A filter index out of range asks for every class.
  EXPECT_NE(ModelPartsUnit(s, "model.h", RunNeeds{.filter = 9}).find("kFilter = -1;"),
            std::string::npos);
}

TEST(ModelSource, CppHeaderIsIncludedByPathWithoutATunerUnit) {
  TempDir dir;
  const std::string header = Source("tests/plugin/data/spring.h");
  const RunResult r = RunEstlab("model source '" + header + "' --out gen", dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(ReadFile(dir.File("gen/model.h")).find("#include \"" + header + "\"\n"),
            std::string::npos);
  EXPECT_NE(ReadFile(dir.File("gen/entry.cpp"))
                .find("#ifndef ESTLAB_MODEL_TYPE\n#define ESTLAB_MODEL_TYPE ESTLAB_MODEL_TYPE"),
            std::string::npos);
  EXPECT_FALSE(dir.Exists("gen/tune.cpp"));
}

TEST(ModelSource, BadInputExits2AndWritesNothing) {
  TempDir dir;
  RunResult r =
      RunEstlab("model source '" + Source("examples/models/pendulum.model") + "'", dir.path());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err, "estlab: error: model source: give --out DIR\n");
  std::ofstream(dir.File("bad.model")) << "[model]\nname = bad\n[states]\nx = [m]\n";
  r = RunEstlab("model source bad.model --out gen", dir.path());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("bad.model:"), std::string::npos) << r.err;
  EXPECT_FALSE(dir.Exists("gen"));
}

// Entries as ESTLAB_DEFINE_LINKED_MODEL registers them.
ModelEntry Named(const std::string& name) {
  ModelEntry m;
  m.name = name;
  return m;
}
const ModelEntry& LinkedNoTuner() {
  static const ModelEntry e = Named("linked-no-tuner");
  return e;
}
const ModelEntry& LinkedTwiceA() {
  static const ModelEntry e = Named("linked-twice");
  return e;
}
const ModelEntry& LinkedTwiceB() {
  static const ModelEntry e = Named("linked-twice");
  return e;
}

TEST(LinkedModel, IsFoundByNameAndSaysWhenItsTunerIsMissing) {
  RegisterLinkedModel(&LinkedNoTuner);
  EXPECT_EQ(&FindModel("linked-no-tuner"), &LinkedNoTuner());
  EXPECT_EQ(AllModels().back(), &LinkedNoTuner());
  try {
    FindModel("linked-no-tuner", {.tuner = true});
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("linked without its tuner"), std::string::npos);
  }
  RegisterLinkedModel(&LinkedTwiceA);
  RegisterLinkedModel(&LinkedTwiceB);
  EXPECT_THROW(FindModel("linked-twice"), InputError);
  EXPECT_EQ(&FindModel("pendulum"), AllModels().front());
}

}  // namespace
}  // namespace estlab::testing
