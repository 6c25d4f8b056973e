% momentid's Octave functions against the command line on the same records, and every class of
% error with its identifier and message. Run by CTest (octave.functions) with MOMENTID_OCTAVE
% (the built functions), MOMENTID (the program) and MOMENTID_SOURCE (the checkout) set; prints
% "octave tests: N passed, M failed".
1;

function check(condition, what)
  global passed failed
  if condition
    passed = passed + 1;
  else
    failed = failed + 1;
    fprintf('FAILED: %s\n', what);
  end
end

% Runs the program with ARGS; its standard output.
function out = program(args)
  [status, out] = system([getenv('MOMENTID') ' ' args ' 2>/dev/null']);
  if status ~= 0
    error('test:program', 'momentid %s: exit status %d', args, status);
  end
end

% The error F throws: its identifier and message ('' when none).
function [id, message] = thrown(f)
  id = '';
  message = '';
  try
    f();
  catch e
    id = e.identifier;
    message = e.message;
  end
end

function check_error(f, id, pattern, what)
  [got, message] = thrown(f);
  check(strcmp(got, id) && ~isempty(regexp(message, pattern, 'once')), ...
        sprintf('%s: expected %s matching "%s", got %s "%s"', what, id, pattern, got, message));
end

% The numbers of a CSV file the program wrote: after its metadata lines and its header.
function values = read_csv(path)
  lines = strsplit(fileread(path), "\n");
  header = find(~strncmp(lines, '#', 1), 1);
  values = dlmread(path, ',', header, 0);
end

% |a - b| <= tol * max(1, |b|), element by element, for equally long vectors.
function ok = close_to(a, b, tol)
  ok = numel(a) == numel(b) && all(abs(a(:) - b(:)) <= tol * max(1, abs(b(:))));
end

global passed failed
passed = 0;
failed = 0;
addpath(getenv('MOMENTID_OCTAVE'));
source = getenv('MOMENTID_SOURCE');
duffing = fullfile(source, 'models', 'duffing.mom');
work = tempname();
mkdir(work);
record = fullfile(work, 'duffing.csv');
program(sprintf('simulate %s --samples 40000 --input x=ma:K=10,w=0.1,sigma=20 -o %s', ...
                duffing, record));

% --- identify: the same estimates as the command line ------------------------------------------
cli = jsondecode(program(sprintf('identify %s %s --format json', duffing, record)));
r = momentid_identify(duffing, record);
names = {'c', 'k', 'eps'};
expected = cellfun(@(n) cli.parameters.(n).estimate, names)';
errors = cellfun(@(n) cli.parameters.(n).std_error, names)';
check(isequal(r.param_names, names'), 'identify: param_names in the model''s order');
check(close_to(r.params, expected, 1e-12), 'identify from the file: estimates as the command line');
check(close_to(r.bse, errors, 1e-12), 'identify from the file: standard errors as the command line');
check(close_to(r.parameters.k.estimate, cli.parameters.k.estimate, 1e-12), 'identify: parameters.k.estimate');
check(close_to(r.parameters.k.ci95, cli.parameters.k.ci95', 1e-12), 'identify: parameters.k.ci95');
check(strcmp(r.diagnostics.status, cli.diagnostics.status), 'identify: diagnostics.status');
check(isequal(size(r.diagnostics.covariance), [3 3]), 'identify: the covariance as a 3x3 matrix');
check(isstruct(r.moments) && isfield(r.moments, 'name'), 'identify: moments as name/value pairs');
check(~isempty(strfind(r.text, 'identified model')), 'identify: the report in text');
check(strcmp(summary(r), r.text), 'summary returns the report');

% The same record as a struct of columns (read from the file): the same estimates.
columns = read_csv(record);
rec = struct('t', columns(:, 1), 'y', columns(:, 2), 'v', columns(:, 3), 'x', columns(:, 4));
rec.metadata = struct('model', 'duffing', 'input_hold', 'zoh');  % as the file says
from_struct = momentid_identify(duffing, rec);
check(close_to(from_struct.params, expected, 1e-12), 'identify from a struct: estimates as the command line');
check(~isempty(strfind(from_struct.text, 'data rec:')), 'identify from a struct: the record named by its variable');
single_rec = rec;
single_rec.x = single(rec.x);
check(numel(momentid_identify(duffing, single_rec).params) == 3, 'identify: a single column is read');

% Options by name, case aside, as the command line's.
cli_fixed = jsondecode(program(sprintf('identify %s %s --format json --fix k=4 --lags 3..60', duffing, record)));
fixed = momentid_identify(duffing, record, 'Fix', struct('k', 4), 'lags', [3 60]);
check(close_to(fixed.params, cellfun(@(n) cli_fixed.parameters.(n).estimate, names)', 1e-12), ...
      'identify with fix and lags: as the command line');
text_fixed = momentid_identify(duffing, record, 'fix', 'k=4', 'lags', '3..60');
check(isequal(text_fixed.params, fixed.params), 'identify: options as the command line''s text');

% Values of other classes and forms, as Python's.
check(isequal(momentid_identify(duffing, record, 'fix', struct('k', 4), 'lags', int32([3 60])).params, ...
              fixed.params), 'identify: an int32 range as a double one');
none = momentid_identify(duffing, record, 'noise', 'none', 'lags', [3 60]);
check(isequal(momentid_identify(duffing, record, 'noise', {}, 'lags', [3 60]).params, none.params) && ...
      isequal(momentid_identify(duffing, record, 'noise', '', 'lags', [3 60]).params, none.params), ...
      'identify: an empty noise list is none, as in Python');
check_error(@() momentid_identify(duffing, record, 'degree', 2^32 + 3), 'momentid:usage', ...
            '^degree: expected a whole number', 'a degree beyond an int');
check_error(@() momentid_identify(duffing, record, 'lags', 5), 'momentid:usage', ...
            '^lags: expected \[FIRST LAST\], found the number 5', 'a range of one number');

% A model's text.
text = fileread(duffing);
check(isequal(momentid_identify(text, record).params, r.params), 'identify: a model''s text');

% --- simulate: the same samples as the command line ------------------------------------------
sim = momentid_simulate(duffing, 'samples', 1000, 'inputs', struct('x', 'ma:K=10,w=0.1,sigma=20'), ...
                        'seed', 7, 'noise', struct('y', 0.02));
program(sprintf('simulate %s --samples 1000 --input x=ma:K=10,w=0.1,sigma=20 --seed 7 --noise y=0.02 -o %s', ...
                duffing, fullfile(work, 'sim.csv')));
written = read_csv(fullfile(work, 'sim.csv'));
check(close_to([sim.t sim.y sim.v sim.x], written, 1e-15), 'simulate: the samples the command line writes');
check(strcmp(sim.metadata.input_hold, 'zoh') && strcmp(sim.metadata.param_k, '4'), 'simulate: the metadata');
lastwarn('');
momentid_simulate(fullfile(source, 'models', 'kozin_4_1c.mom'), 'dt', 0.05, 'samples', 100);
[message, id] = lastwarn();
check(strcmp(id, 'momentid:warning') && strncmp(message, 'the step is coarse', 18), ...
      'simulate: a coarse step warns as Octave does');
path = momentid_simulate(duffing, 'samples', 100, 'path', fullfile(work, 'out.csv'));
check(exist(path, 'file') == 2, 'simulate to a file');

% --- derive --------------------------------------------------------------------------------
eqs = momentid_derive(duffing, 'degree', 3);
check(strcmp(eqs.text, program(sprintf('derive %s --degree 3', duffing))), 'derive: the text the command line prints');
lagged = momentid_derive(duffing, 'lags', [3 45], 'measured', {'y', 'x'});
check(strcmp(lagged.text, program(sprintf('derive %s --lags 3..45 --measured y,x', duffing))), ...
      'derive --lags: the text the command line prints');

% --- validate, check, select ---------------------------------------------------------------
v = momentid_validate(duffing, record, 'params', r);
cli_v = jsondecode(program(sprintf('validate %s %s --format json --set c=%.17g --set k=%.17g --set eps=%.17g', ...
                                   duffing, record, r.params)));
check(strcmp(v.verdict, cli_v.verdict), 'validate: the verdict of the command line');
check(numel(v.series.t) == 40000 && numel(v.series.simulated.y) == 40000 && ...
      sum(v.series.compared) < 40000, 'validate: the series');
check(strcmp(momentid_validate(duffing, record, 'params', r, 'columns', 'y=y').verdict, v.verdict), ...
      'validate: columns as the command line''s text');
c = momentid_check(record, 'model', duffing);
check_error(@() momentid_check(record, 'threads', 5000), 'momentid:usage', '^threads: ', ...
            'check: threads beyond the table''s range');
check_error(@() momentid_simulate(sprintf('state _y\ninput x\nparam a = 1\n_y'' = -a*_y + x'), ...
                                  'samples', 10), 'momentid:usage', '''_y'' cannot name a field', ...
            'simulate: a variable no struct field can hold');
check(~isempty(strfind(c.text, 'y')) && isfield(c, 'channels'), 'check: the statistics');
library = fullfile(source, 'examples', 'select', 'library.mom');
s = momentid_select(library, record);
program(sprintf('select %s %s -o %s', library, record, fullfile(work, 'chosen.mom')));
check(strcmp(s.model_text, fileread(fullfile(work, 'chosen.mom'))), 'select: the chosen model of the command line');
chosen = momentid_identify(s.model_text, record);
check(numel(chosen.params) == numel(s.param_names), 'select: the chosen model identified again');

% --- errors: identifier and message --------------------------------------------------------
check_error(@() momentid_identify(sprintf('model m\nstate y\ny'' = = y'), record), 'momentid:parse', ...
            '^<model>:3:', 'a model that does not parse');
check_error(@() momentid_identify(sprintf('model m\nstate y\nparam a\ny'' = -a*z'), record), ...
            'momentid:model', '^<model>:4:.*z', 'an undeclared name');
check_error(@() momentid_identify(fullfile(work, 'missing.mom'), record), 'momentid:error', ...
            'missing.mom', 'a model file that does not exist');
check_error(@() momentid_identify(duffing, fullfile(source, 'tests', 'data', 'bad_field.csv')), ...
            'momentid:data', 'bad_field.csv:[0-9]+:[0-9]+:', 'a field that is not a number');
check_error(@() momentid_identify(duffing, struct('t', (1:10)', 'y', (1:9)')), 'momentid:usage', ...
            'data.y has 9 values', 'columns of different lengths');
check_error(@() momentid_identify(duffing, 42), 'momentid:usage', ...
            'expected a file name, a cell array of file names or a struct', 'data of another kind');
check_error(@() momentid_identify(duffing, record, 'lgas', [1 3]), 'momentid:usage', ...
            'unknown option ''lgas''; expected one of .*lags', 'an unknown option');
check_error(@() momentid_identify(duffing, record, 'fix', struct('k2', 1)), 'momentid:usage', ...
            '^fix: .*k2', 'a parameter the model lacks');
check_error(@() momentid_identify(duffing, record, 'lags'), 'momentid:usage', ...
            'expected NAME, VALUE pairs', 'a name without a value');
check_error(@() momentid_identify(duffing, record, 'threads', -1), 'momentid:usage', ...
            '^threads: expected a whole number, 0 or more, found the number -1', 'a negative count');
check_error(@() momentid_simulate(duffing, 'params', struct('k', -1e6), 'samples', 100), ...
            'momentid:error', 'blew up|exceeds|not finite', 'a simulation that blows up');
check_error(@() summary(42), 'momentid:usage', 'expected a result', 'summary of something else');

confirm_recursive_rmdir(false);
rmdir(work, 's');
fprintf('octave tests: %d passed, %d failed\n', passed, failed);
