#pragma once
// Numbers read from a saved object map's JSON. nlohmann's get<int>() converts a floating-point
// number with a plain cast, which is undefined behaviour for one out of the type's range (a
// damaged file can hold 1e94 where an id belongs), and get<float>() turns 1e100 into infinity,
// which the next save writes as null and the next load refuses; these reads refuse both instead.
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

namespace slamaware::objectmap {

/// `j` as an integer of type T: an integer, or a float with a whole value, within T's range;
/// otherwise std::runtime_error (the loader then refuses the file by name).
template <class T>
T jsonInt(const nlohmann::json& j) {
  double v = 0;
  if (j.is_number_unsigned()) {
    const uint64_t u = j.get<uint64_t>();
    if (u <= static_cast<uint64_t>(std::numeric_limits<T>::max())) return static_cast<T>(u);
    v = static_cast<double>(u);
  } else if (j.is_number_integer()) {
    const int64_t i = j.get<int64_t>();
    if (i >= static_cast<int64_t>(std::numeric_limits<T>::min()) &&
        (i < 0 || static_cast<uint64_t>(i) <= static_cast<uint64_t>(std::numeric_limits<T>::max())))
      return static_cast<T>(i);
    v = static_cast<double>(i);
  } else if (j.is_number_float()) {
    v = j.get<double>();
    // Whole and inside the range (the bounds as doubles round outwards for 64-bit types, hence <).
    if (std::isfinite(v) && v == std::floor(v) &&
        v >= static_cast<double>(std::numeric_limits<T>::min()) &&
        v < static_cast<double>(std::numeric_limits<T>::max()))
      return static_cast<T>(v);
  } else {
    throw std::runtime_error("object map: expected an integer, got " + std::string(j.type_name()));
  }
  throw std::runtime_error("object map: " + nlohmann::json(v).dump() +
                           " is not an integer of the expected range");
}

/// A JSON array of integers of type T (jsonInt for each).
template <class T>
std::vector<T> jsonInts(const nlohmann::json& j) {
  if (!j.is_array())
    throw std::runtime_error("object map: expected a list of integers, got " +
                             std::string(j.type_name()));
  std::vector<T> out;
  out.reserve(j.size());
  for (const auto& e : j) out.push_back(jsonInt<T>(e));
  return out;
}

/// `j` as a finite number of floating-point type T (an integer or a float within T's range);
/// otherwise std::runtime_error.
template <class T>
T jsonFloat(const nlohmann::json& j) {
  if (!j.is_number())
    throw std::runtime_error("object map: expected a number, got " + std::string(j.type_name()));
  const double v = j.get<double>();
  if (!std::isfinite(v) || std::abs(v) > static_cast<double>(std::numeric_limits<T>::max()))
    throw std::runtime_error("object map: " + j.dump() +
                             " is not a finite number of the expected range");
  return static_cast<T>(v);
}

}  // namespace slamaware::objectmap
