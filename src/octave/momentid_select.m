function r = momentid_select(model, data, varargin)
%MOMENTID_SELECT Choose the terms of a library model that a record wants.
%   R = MOMENTID_SELECT(MODEL, DATA) chooses among the candidate terms of MODEL (a library: a
%   model whose uncertain terms are declared as candidates) as `momentid select` does, and
%   identifies the chosen model.
%   R = MOMENTID_SELECT(MODEL, DATA, NAME, VALUE, ...) sets options as MOMENTID_IDENTIFY takes
%   them, and select's own ('criterion', 'max_terms', ...); 'validation', DATA2 scores the
%   candidates on a second record.
%
%   R has the fields of `momentid select --format json` (R.selected, R.selection.status, and
%   the chosen model's estimates as MOMENTID_IDENTIFY gives them, with R.param_names, R.params
%   and R.bse), R.model_text (the chosen model in the model language: give it to
%   MOMENTID_IDENTIFY or MOMENTID_VALIDATE) and R.text.
%
%   See also MOMENTID_IDENTIFY, SUMMARY.
  try
    name = inputname(2);
  catch
    name = '';
  end
  r = momentid_call('select', model, data, name, varargin{:});
end
