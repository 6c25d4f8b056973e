function r = momentid_check(data, varargin)
%MOMENTID_CHECK Statistics of a record: does it suit the moment method?
%   R = MOMENTID_CHECK(DATA) gives each channel's statistics and autocorrelations, its
%   smoothness and stationarity, as `momentid check` does. R = MOMENTID_CHECK(DATA, 'model',
%   MODEL, ...) checks the record against a model; other options: 'lags', and the record's
%   ('columns', 'dt', 'skip_rows', 'input_hold', ...).
%
%   R has the fields of `momentid check --format json` and R.text.
%
%   See also MOMENTID_IDENTIFY, SUMMARY.
  try
    name = inputname(1);
  catch
    name = '';
  end
  model = [];
  for k = numel(varargin) - 1 - mod(numel(varargin), 2):-2:1  % the names, not the values
    if ischar(varargin{k}) && strcmpi(varargin{k}, 'model')
      model = varargin{k + 1};
      varargin(k:k + 1) = [];
    end
  end
  r = momentid_call('check', model, data, name, varargin{:});
end
