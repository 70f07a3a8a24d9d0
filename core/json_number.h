// Integers read from JSON files we did not write. nlohmann's get<int>() converts a float such as
// 1.3e31 to int, which is undefined behaviour, and wraps integers beyond int's range; fuzzing
// found the first (tests/fuzz/corpus/vae_json). Here either is an error naming file and field.
#pragma once
#include <climits>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

namespace lpt {

/// `j` as an integer in [lo, hi]; otherwise std::runtime_error "<file>: field '<field>': ...".
inline int json_int(const nlohmann::json& j, const std::string& file, const std::string& field, long long lo = INT_MIN,
                    long long hi = INT_MAX) {
    const auto fail = [&](const std::string& what) {
        throw std::runtime_error(file + ": field '" + field + "': " + what);
    };
    if (!j.is_number_integer()) fail("expected an integer, got " + j.dump());
    if (j.is_number_unsigned() ? j.get<unsigned long long>() > static_cast<unsigned long long>(hi)
                               : (j.get<long long>() < lo || j.get<long long>() > hi))
        fail("expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " + j.dump());
    return static_cast<int>(j.get<long long>());
}

}  // namespace lpt
