function r = momentid_identify(model, data, varargin)
%MOMENTID_IDENTIFY Estimate a model's parameters from a record, with standard errors.
%   R = MOMENTID_IDENTIFY(MODEL, DATA) estimates the unknown parameters of MODEL from the
%   record DATA as `momentid identify` does, with its defaults.
%   R = MOMENTID_IDENTIFY(MODEL, DATA, NAME, VALUE, ...) sets options, named as the Python
%   module's keywords (case does not matter): 'lags', [3 40]; 'fix', struct('m', 1);
%   'columns', struct('y', 'disp_mm', 'x', 'force'); 'dt', 1/2048; 'integrate', 'y'; ...
%   (the list: docs/octave.md, and `momentid identify --help`).
%
%   MODEL is a model file (a path ending in .mom) or the text of a model. DATA is a file name
%   (CSV, binary, .npy, .mat, HDF5), a cell array of file names read as one record, a struct
%   of column vectors (fields named as the model's variables, t the time; a field `metadata`
%   as momentid_simulate gives it), or a table.
%
%   R has the fields of `momentid identify --format json`: R.parameters.k.estimate,
%   R.parameters.k.std_error, R.parameters.k.ci95, R.diagnostics.status, ...; and
%   R.param_names, R.params, R.bse (column vectors in the model's order), and R.text, the
%   report as the command line prints it (summary(R) prints it).
%
%   Errors have identifiers: momentid:parse, momentid:model, momentid:data, momentid:usage,
%   momentid:error; Ctrl-C stops a pass.
%
%   Example:
%     model = 'models/duffing.mom';
%     rec = momentid_simulate(model, 'samples', 2e5, 'inputs', struct('x', 'ma:K=10,w=0.1,sigma=20'));
%     r = momentid_identify(model, rec);
%     summary(r)
%
%   See also MOMENTID_SIMULATE, MOMENTID_SELECT, MOMENTID_VALIDATE, MOMENTID_DERIVE, SUMMARY.
  try
    name = inputname(2);
  catch
    name = '';
  end
  r = momentid_call('identify', model, data, name, varargin{:});
end
