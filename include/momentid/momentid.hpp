#pragma once
// Everything momentid offers, in one header: the model language, the moment equations, data
// sources and files, the moment accumulator, the solver, the simulator, and the identify and
// check calls that put them together.
//
// Threads: the model, the equations and the calls that make them use GiNaC, whose shared
// reference counts are not thread-safe. Call the library from one thread at a time (each pass
// reads on threads of its own, RecordOptions::control); a front end that runs calls from several
// threads serialises them and may let others run while a pass reads (PassControl::around_pass).

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
#include "momentid/metadata.hpp"
#include "momentid/model.hpp"
#include "momentid/model_file.hpp"
#include "momentid/moment.hpp"
#include "momentid/parameters.hpp"
#include "momentid/random.hpp"
#include "momentid/reader.hpp"
#include "momentid/record_options.hpp"
#include "momentid/simulate.hpp"
#include "momentid/types.hpp"
#include "momentid/validate.hpp"
#include "momentid/version.hpp"
#include "momentid/writer.hpp"
