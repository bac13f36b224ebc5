#pragma once
// A small reader of NumPy's `.npy` files (what np.save writes: one array per file), enough for the
// target grids PlasticineLab ships. No packaged C++ library reads the format, and it is short:
//
//   bytes 0-5   the magic string: byte 0x93, then the letters NUMPY
//   byte 6, 7   the format version, major and minor: 1.0, 2.0 or 3.0
//   next        the header's length in bytes, little-endian: 2 bytes in version 1, 4 bytes in 2 and 3
//   header      a Python dict literal, e.g. {'descr': '<f8', 'fortran_order': False, 'shape': (64, 64, 64), }
//               padded with spaces and ended by a newline; version 3 only allows UTF-8 in it
//   data        the values, back to back, each as `descr` says ('<f8': little-endian IEEE double,
//               '<f4': little-endian IEEE float), in C order (the last index fastest) unless
//               fortran_order is True (the first index fastest); as many as the shape's product
//
// read_npy() takes versions 1.0, 2.0 and 3.0, dtypes '<f8' and '<f4' (a float becomes the double
// of the same value), C order only (a Fortran-order file is refused: PlasticineLab saves C order,
// and np.ascontiguousarray makes any array C order), and refuses a file with bytes after the data.
// Every refusal is a dsb::UsageError with one line "PATH: problem".
#include <cstddef>
#include <string>
#include <vector>

namespace dsb::mpm {

struct NpyArray {
  std::vector<std::size_t> shape;  // () for a single value
  std::vector<double> values;      // shape's product of values, C order
  std::string dtype;               // as the file declares it: "<f8" or "<f4"
};

// The shape as Python prints it: "(64, 64, 64)", "(5,)", "()".
std::string npy_shape_text(const std::vector<std::size_t>& shape);

// Reads an .npy file (format above). Throws UsageError naming the file and the problem: missing or
// unreadable file, not .npy (bad magic), an unsupported version, a malformed or truncated header,
// an unsupported dtype, Fortran order, more than 2^27 values, data shorter than the shape needs,
// bytes after the data.
NpyArray read_npy(const std::string& path);

}  // namespace dsb::mpm
