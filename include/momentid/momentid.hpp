#pragma once
// Everything momentid offers, in one header: the model language, the moment equations, data
// sources and files, the moment accumulator, the solver, the simulator, and the identify and
// check calls that put them together.
//
// Threads: the library may be called from several threads at once. The model, the equations and
// the calls that make them use GiNaC, whose shared reference counts are not thread-safe, so those
// calls hold one process-wide lock (algebra_lock.hpp) and run their symbolic parts one at a time;
// identify and check let go of it while their data pass reads, which then overlaps with other
// calls. Copying or destroying a Model, MomentSystem, LaggedSystem or HeldInputCorrections takes
// the lock too, so each thread may hold its own and share results; one object read by a thread
// while another changes it needs the caller's own synchronisation, as any C++ value does. A
// program that uses GiNaC objects itself beside such calls holds an AlgebraLock meanwhile.

#include "momentid/accumulator.hpp"
#include "momentid/algebra_lock.hpp"
#include "momentid/check.hpp"
#include "momentid/data_pass.hpp"
#include "momentid/derive.hpp"
#include "momentid/error.hpp"
#include "momentid/estimate.hpp"
#include "momentid/fit.hpp"
#include "momentid/identify.hpp"
#include "momentid/input.hpp"
#include "momentid/json.hpp"
#include "momentid/lagged.hpp"
#include "momentid/latent.hpp"
#include "momentid/metadata.hpp"
#include "momentid/model.hpp"
#include "momentid/model_file.hpp"
#include "momentid/moment.hpp"
#include "momentid/option_table.hpp"
#include "momentid/parameters.hpp"
#include "momentid/random.hpp"
#include "momentid/reader.hpp"
#include "momentid/record_options.hpp"
#include "momentid/refine.hpp"
#include "momentid/select.hpp"
#include "momentid/simulate.hpp"
#include "momentid/types.hpp"
#include "momentid/validate.hpp"
#include "momentid/version.hpp"
#include "momentid/writer.hpp"
