// "GROUP=VALUE,..." lists of sensor groups (docs/multirate.md): the
// sensors' rates (--sensor-rate gps=1) and their tuned R kinds
// (--r-param imu=diag,gps=scalar) read their items here.
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

}  // namespace estlab

#endif  // ESTLAB_OPTIONS_GROUP_ITEMS_H_
