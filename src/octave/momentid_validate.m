function r = momentid_validate(model, data, varargin)
%MOMENTID_VALIDATE Simulate a model through a record's inputs and compare it with the record.
%   R = MOMENTID_VALIDATE(MODEL, DATA, 'params', P) simulates MODEL with the parameter values P
%   (a struct of numbers, or a result of MOMENTID_IDENTIFY: its estimates) through the inputs
%   of DATA and compares the response with the measured states, as `momentid validate` does.
%   Without 'params', the model's nominal values. Other options: 'skip', 'lags', 'substeps',
%   'interpolation', 'center', 'plot' (an SVG file), and the record's ('columns', 'dt', ...).
%
%   R has the fields of `momentid validate --format json` (R.verdict, R.outputs, ...), R.text,
%   and R.series: t, run, simulated.(state), measured.(state), inputs.(input) as column vectors
%   and compared, true for the rows the statistics are over.
%
%   Example:
%     r = momentid_validate(model, rec, 'params', momentid_identify(model, rec));
%     plot(r.series.t, r.series.measured.y, r.series.t, r.series.simulated.y)
%
%   See also MOMENTID_IDENTIFY, SUMMARY.
  try
    name = inputname(2);
  catch
    name = '';
  end
  r = momentid_call('validate', model, data, name, varargin{:});
end
