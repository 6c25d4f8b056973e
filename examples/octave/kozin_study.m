% The report's systems (4.1a-d) identified from Octave: Kozin & Kozin (1967), section IV, with
% the moving-average input of K = 10 values weighted 0.1, dt = 0.05 (as examples/seed_study
% chooses it), one record of N samples each; the table of docs/study.md, then the coupled
% oscillator (4.1d) simulated again through its identified parameters and compared with the
% record (momentid_validate), drawn when Octave has a graphics toolkit.
%
%   octave-cli examples/octave/kozin_study.m [N [PLOT.png]]     (from the checkout's root)
%
% Needs the functions built (cmake -DMOMENTID_OCTAVE=ON, target momentid_octave) in
% build/octave, or their folder in MOMENTID_OCTAVE.
1;
folder = getenv('MOMENTID_OCTAVE');
if isempty(folder)
  folder = fullfile(pwd, 'build', 'octave');
end
addpath(folder);
args = argv();
samples = 1e6;
plot_file = '';
if numel(args) >= 1, samples = str2double(args{1}); end
if numel(args) >= 2, plot_file = args{2}; end

truth = struct('kozin_4_1a', struct('a', 1), ...
               'kozin_4_1b', struct('a', 4, 'b', 16), ...
               'kozin_4_1c', struct('a', 5, 'b', 100), ...
               'kozin_4_1d', struct('a', 3, 'b', 9, 'c', 4, 'd', 16));
input = struct('x', 'ma:K=10,w=0.1,sigma=15');
printf('The systems from %d samples (dt = 0.05, zoh-consistent moments)\n', samples);
printf('system   parameter  truth    estimate      std error    relative error\n');
systems = fieldnames(truth);
for s = 1:numel(systems)
  model = fullfile('models', [systems{s} '.mom']);
  rec = momentid_simulate(model, 'dt', 0.05, 'inputs', input, 'samples', samples, ...
                          'seed', 1967);
  r = momentid_identify(model, rec, 'input_hold', 'zoh', 'batches', 50);
  names = fieldnames(truth.(systems{s}));
  for p = 1:numel(names)
    value = truth.(systems{s}).(names{p});
    estimate = r.parameters.(names{p}).estimate;
    printf('(4.1%s)   %-10s %-8g %-13.6g %-12.3g %+.3f%%\n', systems{s}(end), names{p}, value, ...
           estimate, r.parameters.(names{p}).std_error, 100 * (estimate - value) / value);
  end
end

% The coupled oscillator through its identified parameters, against a second record.
model = fullfile('models', 'kozin_4_1d.mom');
rec = momentid_simulate(model, 'dt', 0.05, 'inputs', input, 'samples', 20000, 'seed', 2, ...
                        'noise', struct('y1', 0.02, 'y3', 0.02));
v = momentid_validate(model, rec, 'params', r);
states = fieldnames(v.outputs);
fits = cellfun(@(n) v.outputs.(n).fit_percent, states);
printf('validate (4.1d) on a second record: fit %s\n  %s\n', sprintf('%.2f%% ', fits), v.verdict);
if ~isempty(plot_file)
  if isempty(available_graphics_toolkits())
    printf('no graphics toolkit: no plot\n');
  else
    figure('visible', 'off');
    shown = find(v.series.compared, 400);
    plot(v.series.t(shown), v.series.measured.y3(shown), 'Color', [0.6 0.6 0.6], 'LineWidth', 3, ...
         v.series.t(shown), v.series.simulated.y3(shown), 'r', 'LineWidth', 1);
    xlabel('t'); ylabel('y_3');
    legend('record (2% noise)', 'identified model', 'Location', 'southoutside', 'Orientation', 'horizontal');
    print(plot_file, '-dpngcairo', '-S800,400');
    printf('wrote %s\n', plot_file);
  end
end
