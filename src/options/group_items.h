// "GROUP=VALUE,..." lists of sensor groups (docs/multirate.md): the
// sensors' rates (--sensor-rate gps=1) and their tuned R kinds
// (--r-param imu=diag,gps=scalar) read their items here, and a study's
// `r-diag = imu=..., gps=...` is split into one value per group.
#ifndef ESTLAB_OPTIONS_GROUP_ITEMS_H_
#define ESTLAB_OPTIONS_GROUP_ITEMS_H_

#include <string>
#include <utility>
#include <vector>

namespace estlab {

// The (group, value) items of `text` in order, both trimmed. Throws
// InputError "KEY: expected GROUP=VALUE_NAME, got 'ITEM'" for an item without
// a group name or '=', and "KEY: sensor group 'G' is given twice".
std::vector<std::pair<std::string, std::string>> ParseGroupItems(const std::string& text,
                                                                 const std::string& key,
                                                                 const std::string& value_name);

// The per-group values of one line that holds several groups' R, in order:
// "imu=1,2,3, gps=0.25" -> {"imu=1,2,3", "gps=0.25"}; "imu=1,0;0,1, gps=4" ->
// {"imu=1,0;0,1", "gps=4"}. An item with '=' starts a group and the items
// after it, up to the next, are its values (numbers hold no '='). A study's
// noise section writes `r-diag = imu=..., gps=...` where the command line
// gives --r-diag once per group; text with no '=' is one item, unchanged.
std::vector<std::string> SplitGroupValues(const std::string& text);

}  // namespace estlab

#endif  // ESTLAB_OPTIONS_GROUP_ITEMS_H_
