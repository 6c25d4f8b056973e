#pragma once

// The channels of a lagged pass and the window of its lags: fitted to the moment budget before
// the pass, to the correlation times the pass shows after it.

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "momentid/data_pass.hpp"
#include "momentid/identify.hpp"
#include "momentid/lagged.hpp"

namespace momentid {

// The channels a lagged pass reads: the variables the equations need, states, inputs and
// derivatives, as the pass numbers them, then the functions it computes from them. Under the
// filter that forms states (`integration`), the products of measured states that the equations'
// terms hold (y1^3, and y1 y2 of two lasers, with the lower powers of their noise corrections)
// are computed too, from the raw rows, so that the filter sees them whole: H(y1^3), not
// H(y1)^3 (lagged_rows' `products`). A product with a formed state cannot be formed so.
struct LaggedChannels {
  std::vector<std::string> states, inputs, derivatives;
  std::vector<ComputedChannel> computed;  // over the channels read: functions, then products
  std::vector<int> channel;               // per model variable: its channel, or -1 when not read
  std::map<Monomial, int> products;       // per product (over the channels): its channel
  // Names of the computed channels, in their order: the functions', then "y1^3".
  std::vector<std::string> computed_names;
};
LaggedChannels lagged_channels(
    const Model& model, const LaggedSystem& system,
    const std::optional<IdentifyResult::Integration>& integration = std::nullopt);

// Per measured (or formed) state that the lagged equations read, or derivative column that
// stands for its unmeasured state: the lag at which its autocorrelation first falls below 1/e,
// from the lagged moments C[y;y](s) of the pass; 0 when it stays above across the window, -1
// when the pass did not read them (the state is no instrument).
std::map<std::string, int> correlation_lags(const IdentifyResult& r,
                                            const std::vector<int>& channel);

// The last lag that spans five correlation times of the slowest measured state; four times the
// window when a state stays correlated across it or its correlation was not read. Kept within
// the bounds of the lag options.
int lag_window(const IdentifyResult& r);

// The last lag at which `count` moments over lags first..last would stay within the budget,
// taking them to grow in proportion to the number of lags.
int last_lag_within_budget(int first, int last, std::size_t count);

// Fits the lags and instruments of `lag_options` to IdentifyOptions::kMaxLaggedMoments where the
// user left them to identify: the window shrinks first, to no fewer than LagOptions::kMinSpan
// lags, then instruments go (powers first) until that window fits, which then grows again as
// far as the budget allows. Returns the instruments cut ("4 of the 10 instruments"), or empty;
// throws UsageError naming the options the user gave when these alone exceed the budget.
std::string fit_to_budget(const Model& model, LagOptions& lag_options,
                          const IdentifyOptions& options);

}  // namespace momentid
