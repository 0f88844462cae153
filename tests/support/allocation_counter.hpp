#pragma once
// Counts heap allocations in a test binary: link allocation_counter.cpp into it (it replaces the
// global operator new/delete) and compare allocation_count() around the code under test.
namespace cvo::testing {

long allocation_count();

}  // namespace cvo::testing
