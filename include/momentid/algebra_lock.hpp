#pragma once
// The lock that keeps the computer algebra to one thread at a time.
//
// GiNaC (and CLN beneath it) count the references to its expressions and numbers without
// atomics, and shares some of them between all expressions (the numbers 0, 1, -1, ...). Every
// library call that makes, reads, copies or destroys such objects (parsing a model, deriving
// equations, identify, check, select_terms, simulate, validate, format_* of the equations, the
// constructors of CompiledModel and RecordSimulator) holds this lock;
// identify and check let go of it while their data pass reads, so that calls from several threads
// overlap there. A thread holds it at most once, however deeply the calls nest.
//
// A program that uses GiNaC objects itself beside calls on other threads (a Model's symbols, an
// Equation's expressions, a MomentCombination's numbers, copied out of the library's values)
// holds an AlgebraLock meanwhile.
//
// Example:
//   {
//     AlgebraLock lock;
//     GiNaC::ex e = model.equations()[0].rhs.expand();
//   }

namespace momentid {

// Holds the lock from construction to destruction; taken again by a thread that holds it, it
// costs nothing.
class AlgebraLock {
 public:
  AlgebraLock();
  ~AlgebraLock();
  AlgebraLock(const AlgebraLock&) = delete;
  AlgebraLock& operator=(const AlgebraLock&) = delete;
};

// Lets go of the lock, however many AlgebraLocks of this thread hold it, from construction to
// destruction (a data pass, which touches no GiNaC object); nothing when the thread does not
// hold it.
class AlgebraUnlock {
 public:
  AlgebraUnlock();
  ~AlgebraUnlock();
  AlgebraUnlock(const AlgebraUnlock&) = delete;
  AlgebraUnlock& operator=(const AlgebraUnlock&) = delete;

 private:
  int held_;
};

namespace detail {
// The first and the last member of a value that holds GiNaC objects (Model, MomentSystem,
// LaggedSystem, HeldInputCorrections), so that its copies, moves, assignments and destruction,
// which change the objects' shared reference counts, hold the lock: members are made and
// assigned in the order they are declared and destroyed in the reverse order, so the lock is
// held from AlgebraSpanStart to AlgebraSpanEnd in each.
struct AlgebraSpanStart {
  AlgebraSpanStart();
  AlgebraSpanStart(const AlgebraSpanStart&);
  AlgebraSpanStart& operator=(const AlgebraSpanStart&);
  ~AlgebraSpanStart();
};
struct AlgebraSpanEnd {
  AlgebraSpanEnd();
  AlgebraSpanEnd(const AlgebraSpanEnd&);
  AlgebraSpanEnd& operator=(const AlgebraSpanEnd&);
  ~AlgebraSpanEnd();
};
}  // namespace detail

}  // namespace momentid
