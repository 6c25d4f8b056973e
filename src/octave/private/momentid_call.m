function out = momentid_call(command, varargin)
% Calls the gateway momentid_mex with COMMAND and the arguments, each string object (MATLAB's
% "text") turned into a char row, a cell of them into a cell of char rows, and a table into a
% struct of its columns; raises the error it reports and issues its warnings.
  for k = 1:numel(varargin)
    varargin{k} = plain(varargin{k});
  end
  [out, id, message, warnings] = momentid_mex(command, varargin{:});
  for k = 1:numel(warnings)
    warning('momentid:warning', '%s', warnings{k});
  end
  if ~isempty(id)
    error(struct('identifier', id, 'message', message));
  end
end

function value = plain(value)
  if isa(value, 'string')
    if isscalar(value)
      value = char(value);
    else
      value = cellstr(value);
    end
  elseif isa(value, 'table')
    value = table2struct(value, 'ToScalar', true);
  elseif iscell(value)
    for k = 1:numel(value)
      value{k} = plain(value{k});
    end
  elseif isstruct(value) && isscalar(value)
    names = fieldnames(value);
    for k = 1:numel(names)
      value.(names{k}) = plain(value.(names{k}));
    end
  end
end
