function text = summary(r)
%SUMMARY The report of a momentid result, as the command line prints it.
%   SUMMARY(R) prints the report of R, a result of MOMENTID_IDENTIFY, MOMENTID_SELECT,
%   MOMENTID_VALIDATE, MOMENTID_CHECK or MOMENTID_DERIVE: the table of estimates, the
%   identified model, the diagnostics. TEXT = SUMMARY(R) returns it instead.
  if ~isstruct(r) || ~isscalar(r) || ~isfield(r, 'text') || ~ischar(r.text)
    error('momentid:usage', 'summary: expected a result of a momentid_ function');
  end
  if nargout > 0
    text = r.text;
  else
    fprintf('%s', r.text);
  end
end
