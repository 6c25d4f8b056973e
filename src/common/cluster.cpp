#include "common/cluster.hpp"

#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <thread>

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

// all_gather in communicator `comm`.
std::vector<std::vector<std::uint8_t>> gather_in(MPI_Comm comm,
                                                 const std::vector<std::uint8_t>& bytes) {
  int n = 1;
  MPI_Comm_size(comm, &n);
  // MPI counts in int: a process's share is its accumulator state, far below 2 GB.
  if (bytes.size() > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
    throw std::length_error("all_gather: more than 2 GB from one process");
  }
  const int mine = static_cast<int>(bytes.size());
  std::vector<int> counts(static_cast<std::size_t>(n)), offsets(static_cast<std::size_t>(n));
  MPI_Allgather(&mine, 1, MPI_INT, counts.data(), 1, MPI_INT, comm);
  std::size_t total = 0;
  for (int r = 0; r < n; ++r) {
    offsets[static_cast<std::size_t>(r)] = static_cast<int>(total);
    total += static_cast<std::size_t>(counts[static_cast<std::size_t>(r)]);
  }
  std::vector<std::uint8_t> all(total);
  MPI_Allgatherv(bytes.data(), mine, MPI_BYTE, all.data(), counts.data(), offsets.data(), MPI_BYTE,
                 comm);
  std::vector<std::vector<std::uint8_t>> out;
  for (int r = 0; r < n; ++r) {
    const auto at = all.begin() + offsets[static_cast<std::size_t>(r)];
    out.emplace_back(at, at + counts[static_cast<std::size_t>(r)]);
  }
  return out;
}

}  // namespace

std::vector<std::vector<std::uint8_t>> all_gather(const std::vector<std::uint8_t>& bytes) {
  if (size() == 1) return {bytes};
  return gather_in(MPI_COMM_WORLD, bytes);
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
       gather_in(errors, std::vector<std::uint8_t>(message.begin(), message.end()))) {
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
std::vector<std::vector<std::uint8_t>> all_gather(const std::vector<std::uint8_t>& bytes) {
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
