// CSV reading and writing per number cell (issue 39, done-when 3: reading at
// most 0.3 us and writing at most 0.5 us per cell). The table is what
// `estlab simulate` and `estlab filter --out` write: 12 columns of doubles
// in %.17g, here 100 000 rows of random values of mixed magnitude. The
// counter `cell` is seconds per number cell.
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "src/io/csv_reader.h"
#include "src/io/output_file.h"

namespace estlab {
namespace {

constexpr int kRows = 100000, kCols = 12;

const std::vector<std::vector<double>>& Rows() {
  static const std::vector<std::vector<double>> rows = [] {
    std::mt19937_64 rng(7);
    std::normal_distribution<double> normal;
    std::uniform_int_distribution<int> exponent(-8, 8);
    std::vector<std::vector<double>> out(kRows, std::vector<double>(kCols));
    for (int i = 0; i < kRows; ++i)
      for (int j = 0; j < kCols; ++j)
        out[size_t(i)][size_t(j)] =
            j == 0 ? i * 0.0125 : normal(rng) * std::pow(10.0, exponent(rng));
    return out;
  }();
  return rows;
}

std::vector<std::string> Names() {
  std::vector<std::string> names;
  for (int j = 0; j < kCols; ++j) {
    std::string name = "c";  // += (GCC 12's -Wrestrict false positive on "c" + string)
    name += std::to_string(j);
    names.push_back(name);
  }
  return names;
}

void SetCellCounter(benchmark::State& state) {
  state.counters["cell"] =
      benchmark::Counter(double(kRows) * kCols, benchmark::Counter::kIsIterationInvariantRate |
                                                    benchmark::Counter::kInvert);
}

void BM_CsvWrite(benchmark::State& state) {
  const auto names = Names();
  for (auto _ : state) {
    std::ostringstream out;
    WriteCsv(out, names, Rows());
    benchmark::DoNotOptimize(out.tellp());
  }
  SetCellCounter(state);
}
BENCHMARK(BM_CsvWrite)->Name("Csv/write/100000x12")->Unit(benchmark::kMillisecond);

void BM_CsvRead(benchmark::State& state) {
  std::string file = "estlab_csv_bench_";
  file += std::to_string(::getpid());
  file += ".csv";
  const std::string path = (std::filesystem::temp_directory_path() / file).string();
  {
    std::ofstream out(path, std::ios::binary);
    WriteCsv(out, Names(), Rows());
  }
  for (auto _ : state) benchmark::DoNotOptimize(ReadCsv(path).rows.size());
  std::filesystem::remove(path);
  SetCellCounter(state);
}
BENCHMARK(BM_CsvRead)->Name("Csv/read/100000x12")->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace estlab
