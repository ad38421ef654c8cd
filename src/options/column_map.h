// Data columns mapped onto estlab's names: `--column ours=theirs` of
// `estlab filter` / `estlab tune` and the `column =` key of a study's
// recorded-data scenario, with an optional affine map for data recorded in
// another convention or unit.
//
// Usage:
//   ColumnMap c = ParseColumnMap("theta=angle-pi");   // theta = 1 * angle - pi
//   ColumnMap d = ParseColumnMap("theta=0.0174533*angle_deg");
//   double theta = d.Apply(row[column_of(d.theirs)]);
//
// Grammar (blanks around the parts are ignored):
//   ours=theirs            a plain rename
//   ours=A*theirs          scaled
//   ours=theirs+B, -B      shifted
//   ours=A*theirs+B        both: ours = A * theirs + B
// A and B are numbers (1e-3, -2) or `pi`. THEIRS is the column name; the
// first `+` or `-` after its first character that is followed by nothing but a
// number or `pi` starts the shift, so a name such as `x-pos` stays a name.
//
// WARNING: a column whose name itself ends in "-<number>" (e.g. `a-1`) reads
// as a shift; such a column cannot be mapped.
#ifndef ESTLAB_OPTIONS_COLUMN_MAP_H_
#define ESTLAB_OPTIONS_COLUMN_MAP_H_

#include <string>
#include <vector>

namespace estlab {

// ours = scale * theirs + offset.
struct ColumnMap {
  std::string ours, theirs;
  double scale = 1.0, offset = 0.0;
  double Apply(double value) const { return scale * value + offset; }
};

// Throws InputError("--column: expected ours=[a*]theirs[+-b], got '...'")
// or naming the bad constant.
ColumnMap ParseColumnMap(const std::string& text);

// Each item one map; an `ours` named twice is an error.
std::vector<ColumnMap> ParseColumnMaps(const std::vector<std::string>& items);

}  // namespace estlab

#endif  // ESTLAB_OPTIONS_COLUMN_MAP_H_
