function rec = momentid_simulate(model, varargin)
%MOMENTID_SIMULATE Simulate a model driven by random inputs.
%   REC = MOMENTID_SIMULATE(MODEL) simulates MODEL at its nominal parameter values, each input
%   a moving average of white noise, as `momentid simulate` does.
%   REC = MOMENTID_SIMULATE(MODEL, NAME, VALUE, ...) with options: 'params', struct('k', 4);
%   'inputs', struct('x', 'ma:K=10,w=0.1,sigma=20'); 'dt'; 'samples'; 'burn_in'; 'runs';
%   'seed'; 'noise', struct('y', 0.02) (relative measurement noise); 'observe', {'y', 'x'}.
%
%   REC is a struct of column vectors: t, the observed channels, run (several runs), and
%   metadata, what a file of the record would say of it (dt, input_hold, ...). It is a record
%   the other functions take. With 'path', FILE the record is written to FILE instead (its
%   format from the extension, .csv, .bin, .npy, .mat or .h5, or 'format': csv, bin, npy, mat,
%   mat73 or h5) and REC is the file's name.
%
%   See also MOMENTID_IDENTIFY.
  rec = momentid_call('simulate', model, varargin{:});
end
