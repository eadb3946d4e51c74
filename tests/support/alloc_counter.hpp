// Counts the heap allocations of a test program: linking the object library
// cncore_test_alloc_counter replaces the global operator new of the whole program, so a test can
// show that a real-time path (a motion cycle, a search's advance) allocates nothing.
#pragma once

namespace cncore::testing {

// Calls of operator new so far in this program (every thread).
long allocations();

}  // namespace cncore::testing
