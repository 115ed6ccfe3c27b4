// A cheap look at a STEP or IGES file's text before OCCT parses it: a few
// hundred KB can hold one list of 300,000 items or parentheses nested thousands
// deep, which cost OCCT's parser a minute or its stack; such files are refused
// at once. One linear pass with constant memory; no OCCT.
//
// STEP (ISO 10303-21): entities are counted by their '=' (#12=...) outside
// strings and comments, a list's items by the commas at its own depth, nesting
// by open parentheses. IGES (fixed 80-column records): entities are the
// directory entries (two D records each), a "list" is one entity's parameter
// data (values separated by the parameter delimiter until the record delimiter;
// IGES 5.3 section 2.2.3), and there is no nesting.
#pragma once

#include <cstddef>
#include <iosfwd>
#include <string>

#include "importer/importer.h"

namespace nurbsrt {

struct PrescanLimits {
    // A large assembly has a few million entities; 20 million is ~1 GB of STEP.
    size_t max_entities = 20'000'000;
    // The longest lists of real parts are control-point nets and knot vectors of
    // a few thousand items; AP242 tessellations can reach ~100k coordinates.
    size_t max_list_items = 500'000;
    // Real STEP nests a few levels deep (lists of lists of points); deep nesting
    // only serves to exhaust a recursive parser's stack.
    int max_nesting = 32;
};

struct PrescanReport {
    size_t entities = 0;
    size_t longest_list = 0;
    int deepest_nesting = 0;
};

// Scans the file at `path` of format `format` (step or iges). Throws
// Error(unreadable_file) naming the first limit exceeded, Error(io) when the
// file cannot be read.
PrescanReport prescan_cad_file(const std::string& path, CadFormat format, const PrescanLimits& limits);
// The same over a stream (read to its end), e.g. bytes already in memory.
PrescanReport prescan_cad_stream(std::istream& in, CadFormat format, const PrescanLimits& limits);

}  // namespace nurbsrt
