#pragma once
// The processes of an MPI job: momentid built with MOMENTID_MPI and started by mpirun. Without
// MPI, or with MPI not started, one process.

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace momentid::cluster {

// The MPI library this build uses ("Open MPI 4.1.4"), or empty without MPI.
std::string library();

int rank();
int size();

// Every process's bytes, in rank order: a collective call that every process makes. A process
// waits for the others without spinning, and throws Error when they have not all come within
// `patience` (one has stopped, or is far slower).
std::vector<std::vector<std::uint8_t>> all_gather(const std::vector<std::uint8_t>& bytes,
                                                  std::chrono::steady_clock::duration patience);

// Starts MPI for its lifetime when the build has it and a launcher (mpirun, srun) started this
// process (threads may run; only this one calls MPI).
class Session {
 public:
  Session(int& argc, char**& argv);
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

 private:
  bool started_ = false;
};

// After an error on this process: the messages of every process, in rank order, when they all
// fail within `wait` of each other (the same model or data error, found by each); nullopt when
// some do not, which may be waiting for this one in a pass it will never join.
std::optional<std::vector<std::string>> all_failed(const std::string& message,
                                                   std::chrono::milliseconds wait);

// Ends every process of the job with `status`: for an error the other processes do not share,
// which they would otherwise wait for.
[[noreturn]] void abort(int status);

}  // namespace momentid::cluster
