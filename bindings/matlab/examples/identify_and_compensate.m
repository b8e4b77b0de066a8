% IDENTIFY_AND_COMPENSATE  From a measured record to a compensated trajectory, in MATLAB/Octave.
%
% Identifies the plant model (voltage -> displacement, for IHC and WIHC) and the inverse model
% (displacement -> voltage, for DIHC) of a real piezo micromanipulator from the shared DBO
% record (Aye & Ang 2018, MIT licence: ../shared/data/dbo-micromanipulator beside the
% repository), saves the plant model, compensates a 1 Hz sine with IHC, WIHC and DIHC, scores
% each drive on the identified plant model with the paper's indices, and plots the result.
%
% Run from bindings/matlab after building the MEX file (README.md):
%   addpath(pwd); run(fullfile('examples', 'identify_and_compensate.m'))
% Set `record` (the record's path) or `figure_file` (a PNG to write) before running to change
% them; by default the record is looked up beside the repository and the figure is shown.

if ~exist('record', 'var')
    here = fileparts(mfilename('fullpath'));
    record = fullfile(here, '..', '..', '..', '..', 'shared', 'data', ...
                      'dbo-micromanipulator', 'Model_Vi_Do.dat');
end
data = load(record);             % 200 Hz; column 1: voltage (V), column 5: sensor (um)
v = data(:, 1);
y = data(:, 5);

% Identification: least squares, 10 play operators (the paper's n), the last 20 % held out.
plant = hystcomp.identify(v, y, 'n', 10, 'direction', 'plant');
inverse = hystcomp.identify(v, y, 'n', 10, 'direction', 'inverse');
fprintf('plant model:   fit %.3f %% RMS of the displacement range, held out %.3f %%\n', ...
        plant.report.fit.rms_percent, plant.report.holdout.rms_percent);
fprintf('inverse model: fit %.3f %% RMS of the voltage range, held out %.3f %%\n', ...
        inverse.report.fit.rms_percent, inverse.report.holdout.rms_percent);
model_file = [tempname() '-dbo-plant.json'];   % a name of its own: /tmp is shared
hystcomp.save_model(plant, model_file);   % for `hystcomp compensate --model` or Simulink
fprintf('plant model written to %s\n', model_file);

% A desired trajectory inside the fitted displacement range, from its bottom: 1 Hz for 2 s at
% 1 kHz (the compensators are rate independent; 2001 samples give e_mhe its 100 bins).
t = (0:1e-3:2)';
lo = plant.report.output.min;
hi = plant.report.output.max;
yd = (lo + hi) / 2 + 0.4 * (hi - lo) * sin(2 * pi * t - pi / 2);

% Three compensators. A Compensator keeps its state from call to call, as in a control loop.
ihc = hystcomp.Compensator(plant, 'ihc');
v_ihc = ihc.process(yd);
[v_wihc, diagnostics] = hystcomp.compensate(plant, 'wihc', yd);
v_dihc = hystcomp.compensate(inverse, 'dihc', yd);
% Uncompensated: the straight line through the record's (voltage, displacement) ranges.
v_line = min(v) + (yd - min(y)) * (max(v) - min(v)) / (max(y) - min(y));
fprintf('drive limits [%g, %g] V, %d samples saturated\n', diagnostics.limits, ...
        diagnostics.saturated);

% Score each drive on the identified plant model (not the device): how well each compensator
% inverts the model (IHC and WIHC exactly; DIHC up to the two models' mismatch).
drives = {v_line, v_ihc, v_wihc, v_dihc};
names = {'uncompensated', 'IHC', 'WIHC', 'DIHC'};
fprintf('%-14s %9s %9s %9s   (%% of the desired range, on the plant model)\n', '', 'e_m', ...
        'e_rms', 'e_mhe');
for k = 1:numel(drives)
    response = hystcomp.predict(plant, drives{k});
    fprintf('%-14s %9.4f %9.4f %9.4f\n', names{k}, hystcomp.e_m(yd, response), ...
            hystcomp.e_rms(yd, response), hystcomp.e_mhe(yd, response));
end

% Plot: the drives over time, and the response against the desired position.
if exist('OCTAVE_VERSION', 'builtin') && isempty(getenv('DISPLAY'))
    figure_handle = figure('visible', 'off');   % headless Octave: draw off screen
else
    figure_handle = figure();
end
subplot(1, 2, 1);
plot(t, v_line, t, v_ihc, t, v_dihc);
xlabel('time (s)'); ylabel('drive (V)'); legend('uncompensated', 'IHC', 'DIHC');
title('drive voltage');
subplot(1, 2, 2);
plot(yd, hystcomp.predict(plant, v_line), yd, hystcomp.predict(plant, v_ihc));
xlabel('desired (um)'); ylabel('predicted displacement (um)');
legend('uncompensated', 'IHC', 'location', 'northwest');
title('hysteresis removed');
if exist('figure_file', 'var')
    print(figure_handle, '-dpng', figure_file);
    fprintf('figure written to %s\n', figure_file);
end
delete(ihc);
