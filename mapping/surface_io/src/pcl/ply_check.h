// Validation of a PLY file before PCL reads it (PRIVATE to driftcorr_surface_io).
//
// PCL 1.13's PLYReader asserts (and so aborts the process: Debian builds it with assertions) or
// writes out of bounds on files it does not expect: a header keyword after a blank (found by
// fuzzing: assert in objInfoCallback), an `alpha` without `red`, a `blue` without `red`, a list
// property in the vertex element, obj_info num_cols/num_rows that disagree with the vertex count, a
// range_grid element with indices past the vertices. So PCL only sees files checked here: the
// header in the form of the PLY 1.0 specification written one word per blank, the vertex element
// in the forms PCL handles, and the body walked to its last byte.
#pragma once

#include <cstddef>
#include <string>

namespace driftcorr::internal {

/// What the check learned from a valid file.
struct PlyLayout {
    std::size_t vertex_count = 0;  ///< "element vertex N"
};

/// Checks the file at `path` as described above; throws InputError (naming the file, the line of
/// the header or the body where known, and what is wrong) when it is not a PLY file PCL can read
/// safely. Accepted: format ascii, binary_little_endian or binary_big_endian 1.0; comment and
/// obj_info lines; any elements with scalar and list properties of the PLY types (list counts of
/// an integer type), except range_grid; a vertex element with scalar x, y and z, no list property,
/// colours as the uchar triple red green blue (or diffuse_*) with an optional alpha after it; the
/// body exactly as long as the header declares (ASCII: one line per element instance, numbers
/// separated by blanks; binary: every byte accounted for).
PlyLayout PrecheckPly(const std::string& path);

}  // namespace driftcorr::internal
