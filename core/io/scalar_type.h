// The scalar types of binary mesh formats (PLY properties, VTK DataArrays): their sizes, and
// one value read from bytes in either byte order. Each format keeps its own type names.
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "io/readers.h"

namespace vdbwrap::io::detail {

// String: VTK's character arrays (read as bytes, never as numbers).
enum class ScalarType { I8, U8, I16, U16, I32, U32, I64, U64, F32, F64, String };

inline size_t scalar_size(ScalarType t) {
  switch (t) {
    case ScalarType::I8:
    case ScalarType::U8:
    case ScalarType::String:
      return 1;
    case ScalarType::I16:
    case ScalarType::U16:
      return 2;
    case ScalarType::I32:
    case ScalarType::U32:
    case ScalarType::F32:
      return 4;
    default:
      return 8;
  }
}

inline bool is_integer(ScalarType t) { return t != ScalarType::F32 && t != ScalarType::F64 && t != ScalarType::String; }

// How a read array is held in MeshData: bytes stay bytes, other integers Int32, reals doubles.
inline DataArray::Type data_type(ScalarType t) {
  if (t == ScalarType::U8) return DataArray::Type::UInt8;
  return is_integer(t) ? DataArray::Type::Int32 : DataArray::Type::Float64;
}

// How an extra array's values are written: the type's name in PLY and in VTK, and its size.
struct WrittenType {
  const char* ply;
  const char* vtk;
  size_t bytes;
};
inline WrittenType written_type(DataArray::Type t) {
  switch (t) {
    case DataArray::Type::Int32:
      return {"int", "Int32", 4};
    case DataArray::Type::UInt8:
      return {"uchar", "UInt8", 1};
    case DataArray::Type::Float64:
      break;
  }
  return {"double", "Float64", 8};
}

// The value of type t at p, as T. An integer T gets UInt64 values above INT64_MAX as INT64_MAX
// (out of any index's range anyway); every smaller integer type is exact in a double.
template <class T>
T load_scalar(const char* p, ScalarType t, bool little_endian) {
  switch (t) {
    case ScalarType::I8:
      return T(int8_t(*p));
    case ScalarType::U8:
      return T(uint8_t(*p));
    case ScalarType::I16:
      return T(load<int16_t>(p, little_endian));
    case ScalarType::U16:
      return T(load<uint16_t>(p, little_endian));
    case ScalarType::I32:
      return T(load<int32_t>(p, little_endian));
    case ScalarType::U32:
      return T(load<uint32_t>(p, little_endian));
    case ScalarType::I64:
      return T(load<int64_t>(p, little_endian));
    case ScalarType::U64: {
      uint64_t v = load<uint64_t>(p, little_endian);
      if constexpr (std::is_integral_v<T>) v = std::min<uint64_t>(v, uint64_t(INT64_MAX));
      return T(v);
    }
    case ScalarType::F32:
      return T(load<float>(p, little_endian));
    case ScalarType::F64:
      return T(load<double>(p, little_endian));
    case ScalarType::String:
      break;
  }
  return T(0);
}

}  // namespace vdbwrap::io::detail
