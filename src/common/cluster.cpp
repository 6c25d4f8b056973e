#include "common/cluster.hpp"

#include <algorithm>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <thread>

#include "momentid/error.hpp"

#ifdef MOMENTID_WITH_MPI
#include <mpi.h>
#endif

namespace momentid::cluster {

#ifdef MOMENTID_WITH_MPI

namespace {

// Errors are agreed on in a communicator of their own, apart from the passes' collectives that
// other processes may be in.
MPI_Comm errors = MPI_COMM_NULL;

bool running() {
  int started = 0, ended = 0;
  MPI_Initialized(&started);
  MPI_Finalized(&ended);
  return started != 0 && ended == 0;
}

}  // namespace

std::string library() {
#ifdef OMPI_MAJOR_VERSION
  return "Open MPI " + std::to_string(OMPI_MAJOR_VERSION) + "." +
         std::to_string(OMPI_MINOR_VERSION) + "." + std::to_string(OMPI_RELEASE_VERSION);
#else
  return "MPI " + std::to_string(MPI_VERSION) + "." + std::to_string(MPI_SUBVERSION);
#endif
}

int rank() {
  int r = 0;
  if (running()) MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}

int size() {
  int n = 1;
  if (running()) MPI_Comm_size(MPI_COMM_WORLD, &n);
  return n;
}

namespace {

// Waits for `request` without spinning (MPI's blocking calls poll at full speed while a process
// waits for slower ones); throws when `deadline` passes first.
void wait_for(MPI_Request& request, std::chrono::steady_clock::time_point deadline,
              std::chrono::steady_clock::duration patience) {
  auto pause = std::chrono::microseconds(50);
  for (int done = 0;;) {
    MPI_Test(&request, &done, MPI_STATUS_IGNORE);
    if (done != 0) return;
    if (std::chrono::steady_clock::now() > deadline) {
      const auto seconds = std::chrono::duration_cast<std::chrono::seconds>(patience).count();
      throw Error("waited " + std::to_string(seconds) +
                  " s for the other processes of the job to finish their part of the pass (one "
                  "has stopped, or is far slower): the job ends");
    }
    std::this_thread::sleep_for(pause);
    pause = std::min<std::chrono::microseconds>(2 * pause, std::chrono::milliseconds(10));
  }
}

// all_gather in communicator `comm`.
std::vector<std::vector<std::uint8_t>> gather_in(MPI_Comm comm,
                                                 const std::vector<std::uint8_t>& bytes,
                                                 std::chrono::steady_clock::duration patience) {
  const auto deadline = std::chrono::steady_clock::now() + patience;
  int n = 1;
  MPI_Comm_size(comm, &n);
  // MPI counts in int: a process's share is its accumulator state, far below 2 GB.
  if (bytes.size() > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
    throw std::length_error("all_gather: more than 2 GB from one process");
  }
  const int mine = static_cast<int>(bytes.size());
  std::vector<int> counts(static_cast<std::size_t>(n)), offsets(static_cast<std::size_t>(n));
  MPI_Request request;
  MPI_Iallgather(&mine, 1, MPI_INT, counts.data(), 1, MPI_INT, comm, &request);
  wait_for(request, deadline, patience);
  std::size_t total = 0;
  for (int r = 0; r < n; ++r) {
    offsets[static_cast<std::size_t>(r)] = static_cast<int>(total);
    total += static_cast<std::size_t>(counts[static_cast<std::size_t>(r)]);
  }
  std::vector<std::uint8_t> all(total);
  MPI_Iallgatherv(bytes.data(), mine, MPI_BYTE, all.data(), counts.data(), offsets.data(), MPI_BYTE,
                  comm, &request);
  wait_for(request, deadline, patience);
  std::vector<std::vector<std::uint8_t>> out;
  for (int r = 0; r < n; ++r) {
    const auto at = all.begin() + offsets[static_cast<std::size_t>(r)];
    out.emplace_back(at, at + counts[static_cast<std::size_t>(r)]);
  }
  return out;
}

}  // namespace

std::vector<std::vector<std::uint8_t>> all_gather(const std::vector<std::uint8_t>& bytes,
                                                  std::chrono::steady_clock::duration patience) {
  if (size() == 1) return {bytes};
  return gather_in(MPI_COMM_WORLD, bytes, patience);
}

std::optional<std::vector<std::string>> all_failed(const std::string& message,
                                                   std::chrono::milliseconds wait) {
  if (size() == 1 || errors == MPI_COMM_NULL) return std::vector<std::string>{message};
  MPI_Request request;
  MPI_Ibarrier(errors, &request);
  const auto deadline = std::chrono::steady_clock::now() + wait;
  for (int done = 0;;) {
    MPI_Test(&request, &done, MPI_STATUS_IGNORE);
    if (done != 0) break;
    if (std::chrono::steady_clock::now() > deadline) return std::nullopt;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  std::vector<std::string> out;
  for (const auto& bytes :
       gather_in(errors, std::vector<std::uint8_t>(message.begin(), message.end()), wait)) {
    out.emplace_back(bytes.begin(), bytes.end());
  }
  return out;
}

Session::Session(int& argc, char**& argv) {
  // Only a process that a launcher started (Open MPI's mpirun, or a PMI one such as srun) has
  // others: a lone process does not pay for starting MPI.
  if (std::getenv("OMPI_COMM_WORLD_SIZE") == nullptr && std::getenv("PMI_SIZE") == nullptr &&
      std::getenv("PMIX_RANK") == nullptr) {
    return;
  }
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  MPI_Comm_dup(MPI_COMM_WORLD, &errors);
  started_ = true;
}

Session::~Session() {
  if (!started_) return;
  MPI_Comm_free(&errors);
  MPI_Finalize();
}

void abort(int status) {
  if (running()) MPI_Abort(MPI_COMM_WORLD, status);
  std::exit(status);
}

#else

std::string library() { return {}; }
int rank() { return 0; }
int size() { return 1; }
std::vector<std::vector<std::uint8_t>> all_gather(const std::vector<std::uint8_t>& bytes,
                                                  std::chrono::steady_clock::duration) {
  return {bytes};
}
std::optional<std::vector<std::string>> all_failed(const std::string& message,
                                                   std::chrono::milliseconds) {
  return std::vector<std::string>{message};
}
Session::Session(int&, char**&) {}
Session::~Session() = default;
void abort(int status) { std::exit(status); }

#endif

}  // namespace momentid::cluster
