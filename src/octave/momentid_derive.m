function eqs = momentid_derive(model, varargin)
%MOMENTID_DERIVE The moment equations of a model: a linear system in its parameters.
%   EQS = MOMENTID_DERIVE(MODEL) derives the zero-lag moment equations as `momentid derive`
%   does; options: 'degree', 'multipliers' ({'y', 'y^3'}); 'lags', [1 20] for the lagged
%   (instrumental) equations, with 'instruments' and 'measured'.
%
%   EQS has the fields of `momentid derive --format json`, EQS.text (the equations as the
%   command line prints them) and EQS.latex.
%
%   See also MOMENTID_IDENTIFY.
  eqs = momentid_call('derive', model, varargin{:});
end
