function test_hystcomp(mexdir, library, root, dbo_record, cli_plant, cli_inverse)
%TEST_HYSTCOMP The MATLAB/Octave binding's tests, with assertions.
%   test_hystcomp(MEXDIR, LIBRARY, ROOT, DBO_RECORD, CLI_PLANT, CLI_INVERSE) runs every test
%   against the MEX file in MEXDIR (built by build.m against the static library LIBRARY), with
%   the repository at ROOT, and prints one line per test. DBO_RECORD is the shared
%   Model_Vi_Do.dat and CLI_PLANT, CLI_INVERSE the model files `hystcomp identify` wrote from
%   it (plant and inverse, the command line's defaults); give '' for all three to skip that
%   test (it says so). Ends with "ALL PASSED", or exits Octave with status 1 after listing the
%   failures. Run by crates/cli/tests/matlab.rs (so that `cargo test --workspace` runs it).
addpath(fullfile(root, 'bindings', 'matlab'));
addpath(mexdir);
tests = {
    'round_trip_table1', @() round_trip_table1(root)
    'identification_matches_the_cli', ...
        @() identification_matches_the_cli(dbo_record, cli_plant, cli_inverse)
    'models_round_trip_through_files_and_structs', ...
        @() models_round_trip_through_files_and_structs(root)
    'models_with_creep_and_vibration_run_their_chain', ...
        @() models_with_creep_and_vibration_run_their_chain(root)
    'indices_match_a_plain_reference', @() indices_match_a_plain_reference()
    'every_bad_argument_raises_an_error_with_an_identifier', ...
        @() every_bad_argument_raises_an_error_with_an_identifier(root)
    'freed_and_forged_handles_are_refused', @() freed_and_forged_handles_are_refused(root)
    'simulink_s_function_steps_the_compensator', ...
        @() simulink_s_function_steps_the_compensator(root, mexdir, library)
};
failures = {};
for k = 1:size(tests, 1)
    name = tests{k, 1};
    try
        note = tests{k, 2}();
        if isempty(note)
            fprintf('PASS %s\n', name);
        else
            fprintf('PASS %s (%s)\n', name, note);
        end
    catch e
        failures{end + 1} = sprintf('%s: %s (%s)', name, e.message, e.identifier); %#ok<AGROW>
        fprintf('FAIL %s\n  %s\n', name, failures{end});
    end
end
% Every compensator the tests made is gone.
if hystcomp_mex('live_compensators') ~= 0
    failures{end + 1} = sprintf('%d compensator(s) still alive', hystcomp_mex('live_compensators'));
end
if isempty(failures)
    fprintf('ALL PASSED\n');
else
    fprintf('%d FAILED:\n', numel(failures));
    fprintf('  %s\n', failures{:});
    exit(1);
end
end

% ---------------------------------------------------------------------------------------------

function y = reference_mpim(model, x)
% Eq. (4) written out plainly, in the model's physical units, from zero memory (eq. (1)): the
% independent check of the round trip.
in = model.input; out = model.output;
r = model.thresholds(:); b = model.weights(:);
w = zeros(size(r));
y = zeros(size(x));
for k = 1:numel(x)
    u = (x(k) - in.offset) / in.scale;
    w = max(u - r, min(u, w)); % one-sided play operators, eq. (2)
    y(k) = out.offset + out.scale * (model.a1 * u^3 + model.a2 * u + b' * w);
end
end

function check(condition, varargin)
if ~condition
    error('test:failed', varargin{:});
end
end

function note = round_trip_table1(root)
% Table 1 of the paper: P[C[y_d]] = y_d within 1e-9 um for IHC and WIHC, by the library's
% forward model and by the plain one above; step, process and compensate agree.
model = hystcomp.load_model(fullfile(root, 'models', 'table1-plant.json'));
t = (0:1e-4:2)';
yd = 37.5 + 30 * sin(2 * pi * t) .* exp(-t / 4) + 3 * sin(2 * pi * 7 * t);
for method = {'ihc', 'wihc'}
    c = hystcomp.Compensator(model, method{1});
    v = c.process(yd);
    check(all(v >= 0 & v <= 10), '%s: voltage outside [0, 10] V', method{1});
    worst = max(abs(hystcomp.predict(model, v) - yd));
    check(worst < 1e-9, '%s: P[C[y_d]] - y_d up to %g um (library)', method{1}, worst);
    plain = max(abs(reference_mpim(model, v) - yd));
    check(plain < 1e-9, '%s: P[C[y_d]] - y_d up to %g um (plain eq. (4))', method{1}, plain);
    c.reset();
    stepped = zeros(size(yd));
    for k = 1:numel(yd)
        stepped(k) = c.step(yd(k));
    end
    check(isequal(stepped, v), '%s: step differs from process', method{1});
    check(isequal(hystcomp.compensate(model, method{1}, yd), v), '%s: compensate differs', method{1});
    % A row in, a row out.
    check(isequal(size(hystcomp.compensate(model, method{1}, yd')), size(yd')), 'row shape');
    d = c.diagnostics();
    check(d.saturated == 0 && d.non_finite == 0 && isequal(d.limits, [0 10]), 'diagnostics');
    delete(c);
end
% DIHC (Table 2, an inverse model) and the delayed loops stay within their limits.
inverse = hystcomp.load_model(fullfile(root, 'models', 'table2-inverse.json'));
[v, d] = hystcomp.compensate(inverse, 'dihc', yd, [1 9]);
check(all(v >= 1 & v <= 9) && isequal(d.limits, [1 9]), 'dihc limits');
% Table 1's delayed WIHC loop gain is 1.66: the plain loop can ring, so it is refused unless
% allowed explicitly; the guarded loop cannot ring and is built.
try
    hystcomp.Compensator(model, 'wihc-delayed');
    error('test:failed', 'an unstable delayed loop was built without the override');
catch e
    check(strcmp(e.identifier, 'hystcomp:unstableDelay') && ~isempty(strfind(e.message, '1.659')), ...
          'unstable delay refusal: %s %s', e.identifier, e.message);
end
c = hystcomp.Compensator(model, 'wihc-delayed', [], 'AllowUnstableDelay', true);
d = c.diagnostics();
check(abs(d.delayed_loop_gain - 1.66) < 0.01, 'Table 1 delayed WIHC loop gain %g', d.delayed_loop_gain);
v = c.process(yd);
check(all(v >= 0 & v <= 10), 'the allowed delayed WIHC leaves its limits');
delete(c);
c = hystcomp.Compensator(model, 'wihc-guarded');
v = c.process(yd);
d = c.diagnostics();
check(all(v >= 0 & v <= 10) && d.loop_saturated == 0, 'guarded WIHC: limits or loop clamps (%d)', ...
      d.loop_saturated);
delete(c);
note = sprintf('IHC and WIHC within %.1e um', worst);
end

function note = identification_matches_the_cli(dbo_record, cli_plant, cli_inverse)
% The shared DBO record (Aye & Ang 2018), columns 1 (V) and 5 (sensor): with the defaults on
% both sides (least squares, n = 10, hold-out 0.2), the same models and fit figures as
% `hystcomp identify`, to 1e-9 relative.
if isempty(dbo_record)
    note = 'SKIPPED: the shared DBO record is absent';
    return;
end
data = dlmread(dbo_record);
v = data(:, 1);
y = data(:, 5);
pairs = {'plant', cli_plant; 'inverse', cli_inverse};
figures = {};
for k = 1:2
    ours = hystcomp.identify(v, y, 'direction', pairs{k, 1}); % the defaults: the CLI's
    cli = hystcomp.load_model(pairs{k, 2});
    near = @(a, b) all(abs(a(:) - b(:)) <= 1e-9 * max(1, abs(b(:))));
    what = pairs{k, 1};
    check(strcmp(ours.direction, cli.direction), '%s: direction', what);
    check(near(ours.thresholds, cli.thresholds) && near(ours.weights, cli.weights), ...
          '%s: weights differ from the CLI''s', what);
    check(near([ours.a1 ours.a2], [cli.a1 cli.a2]), '%s: a1, a2 differ', what);
    check(near([ours.input.offset ours.input.scale ours.output.offset ours.output.scale], ...
                [cli.input.offset cli.input.scale cli.output.offset cli.output.scale]), ...
          '%s: scales differ', what);
    r = ours.report; q = cli.report;
    check(isequal(r.samples, q.samples), '%s: sample counts differ', what);
    check(near([r.fit.rms r.fit.max r.fit.rms_percent r.holdout.rms r.holdout.rms_percent ...
                 r.min_branch_slope r.condition_number], ...
                [q.fit.rms q.fit.max q.fit.rms_percent q.holdout.rms q.holdout.rms_percent ...
                 q.min_branch_slope q.condition_number]), '%s: fit figures differ', what);
    figures{k} = sprintf('%s fit %.3f %% RMS', what, r.fit.rms_percent); %#ok<AGROW>
end
note = strjoin(figures, ', ');
end

function note = models_round_trip_through_files_and_structs(root)
model = hystcomp.load_model(fullfile(root, 'models', 'table2-inverse.json'));
file = [tempname() '.json'];
cleanup = onCleanup(@() delete(file));
hystcomp.save_model(model, file);
again = hystcomp.load_model(file);
check(isequal(again, model), 'save then load changed the model');
% An identified model keeps its report through a file.
t = (0:1/200:20)';
v = 5 - 5 * exp(-t / 10) .* cos(2 * pi * t);
y = hystcomp.predict(hystcomp.load_model(fullfile(root, 'models', 'table1-plant.json')), v);
fit = hystcomp.identify(v, y + 3, 'n', 6, 'voltage_unit', 'kV');
check(fit.report.fit.rms_percent < 1 && strcmp(fit.input.unit, 'kV'), 'identification');
hystcomp.save_model(fit, file);
again = hystcomp.load_model(file);
check(isequal(again.weights, fit.weights) && isequal(again.report, fit.report), 'report lost');
% The struct is the model: an edit changes the compensator, an invalid edit is refused.
edited = fit;
edited.a2 = NaN;
expect_error(@() hystcomp.compensate(edited, 'ihc', 40), 'hystcomp:invalidArgument');
edited = rmfield(fit, 'weights');
expect_error(@() hystcomp.Compensator(edited, 'ihc'), 'hystcomp:invalidModel');
% A model file's name works wherever a model struct does.
file_v = hystcomp.compensate(file, 'ihc', y(1:50));
check(isequal(file_v, hystcomp.compensate(fit, 'ihc', y(1:50))), 'file name as model');
note = '';
end

function note = models_with_creep_and_vibration_run_their_chain(root)
% Format version 2: Table 1 with a creep link and a vibration link (two samples of delay). The
% struct carries the links, a file keeps them, predict runs the chain and compensate inverts it.
model = hystcomp.load_model(fullfile(root, 'models', 'table1-plant.json'));
check(isempty(model.creep) && isempty(model.vibration) && isempty(model.sample_rate_hz), ...
      'Table 1 has no links');
model.sample_rate_hz = 10000;
model.creep = struct('origin', 0, 'time_constants_s', [0.01; 0.1], 'weights', [0.01; 0.005]);
model.vibration = struct('delay_samples', 2, 'numerator', 0.3, 'denominator', [1; -0.7]);
file = [tempname() '.json'];
cleanup = onCleanup(@() delete(file));
hystcomp.save_model(model, file);
again = hystcomp.load_model(file);
check(isequal(again.creep, model.creep) && isequal(again.vibration, model.vibration) && ...
      again.sample_rate_hz == 10000, 'the links did not survive a file');
% From rest at the creep's origin (from elsewhere the links' initial states differ between the
% inverse and the forward chain: 3 nm decaying over the creep's time constants).
t = (0:1e-4:0.5)';
yd = 25 * (1 - cos(2 * pi * 1.5 * t));
v = hystcomp.compensate(again, 'ihc', yd);
worst = max(abs(hystcomp.predict(again, v) - yd));
check(worst < 1e-3, 'the chain is not inverted: %g um', worst);
% Without its links the same drive misses: the links are used, not dropped.
plain = rmfield(again, {'creep', 'vibration', 'sample_rate_hz'});
check(max(abs(hystcomp.predict(plain, v) - yd)) > 0.05, 'predict ignores the links');
c = hystcomp.Compensator(again, 'ihc');
d = c.diagnostics();
delete(c);
check(d.preview >= 2, 'preview %g', d.preview);
bad = again;
bad.creep = 'fast';
expect_error(@() hystcomp.predict(bad, v), 'hystcomp:invalidModel');
bad = again;
bad.vibration.denominator = [1; -0.5]; % static gain 0.6, not 1
expect_error(@() hystcomp.predict(bad, v), 'hystcomp:invalidArgument');
bad = again;
bad.sample_rate_hz = -1;
expect_error(@() hystcomp.Compensator(bad, 'ihc'), 'hystcomp:invalidArgument');
note = sprintf('round trip within %.1e um, preview %d samples', worst, d.preview);
end

function note = indices_match_a_plain_reference()
rand('seed', 1); %#ok<RAND>
for trial = 1:20
    n = 20 + floor(rand() * 2000);
    yd = cumsum(randn(n, 1));
    y = yd + 0.1 * randn(n, 1);
    range = max(yd) - min(yd);
    e_m = max(abs(y - yd)) / range * 100;
    e_rms = sqrt(mean((y - yd).^2)) / range * 100;
    bins = max(1, floor(n / 10));
    bin = min(floor((yd - min(yd)) / (range / bins)), bins - 1);
    widest = 0;
    for b = 0:bins - 1
        in = y(bin == b);
        if numel(in) >= 2
            widest = max(widest, max(in) - min(in));
        end
    end
    e_mhe = widest / range * 100;
    check(abs(hystcomp.e_m(yd, y) - e_m) <= 1e-12 * e_m, 'e_m');
    check(abs(hystcomp.e_rms(yd, y) - e_rms) <= 1e-12 * e_rms, 'e_rms');
    check(abs(hystcomp.e_mhe(yd, y, bins) - e_mhe) <= 1e-12 * max(e_mhe, 1), 'e_mhe');
end
check(hystcomp.e_mhe(yd, y) == hystcomp.e_mhe(yd, y, 100), 'e_mhe default bins');
note = '';
end

function expect_error(f, id)
% f() must raise an error with identifier `id` and a message.
try
    f();
catch e
    check(strcmp(e.identifier, id), 'expected %s, got %s: %s', id, e.identifier, e.message);
    check(numel(e.message) > 10, '%s: an error without a message', id);
    return;
end
error('test:failed', 'no error raised; expected %s', id);
end

function note = every_bad_argument_raises_an_error_with_an_identifier(root)
plant = fullfile(root, 'models', 'table1-plant.json');
model = hystcomp.load_model(plant);
inverse = hystcomp.load_model(fullfile(root, 'models', 'table2-inverse.json'));
c = hystcomp.Compensator(model, 'ihc');
cleanup = onCleanup(@() delete(c));
yd = 37.5 + 20 * sin((1:100)' / 10);
v = (1:100)' / 10;
broken = [tempname() '.json'];
fid = fopen(broken, 'w'); fprintf(fid, '{"format_version": 1, "a1": '); fclose(fid);
cleanup_file = onCleanup(@() delete(broken));
cases = {
    % wrong class
    @() c.step(single(40)),                          'hystcomp:wrongType'
    @() c.step('4'),                                 'hystcomp:wrongType'
    @() c.process(int32([1 2 3])),                   'hystcomp:wrongType'
    @() c.process({1, 2}),                           'hystcomp:wrongType'
    @() c.process(true(3, 1)),                       'hystcomp:wrongType'
    @() c.process(sparse([1 2 3])),                  'hystcomp:wrongType'
    @() hystcomp.identify(single(v), yd),            'hystcomp:wrongType'
    @() hystcomp.e_m(yd, struct('y', 1)),            'hystcomp:wrongType'
    @() hystcomp.compensate(model, 5, yd),           'hystcomp:wrongType'
    @() hystcomp.Compensator(model, 'ihc', 'abc'),   'hystcomp:wrongType'
    @() hystcomp.Compensator({model}, 'ihc'),        'hystcomp:invalidModel'
    @() hystcomp.load_model(42),                     'hystcomp:wrongType'
    @() hystcomp.identify(v, yd, 'accept_poor_fit', 'yes'), 'hystcomp:wrongType'
    % complex
    @() c.step(40 + 1i),                             'hystcomp:wrongType'
    @() c.process(yd + 1i),                          'hystcomp:wrongType'
    @() hystcomp.identify(v + 1i, yd),               'hystcomp:wrongType'
    @() hystcomp.e_rms(yd, yd * (1 + 1i)),           'hystcomp:wrongType'
    % NaN and infinities
    @() c.step(NaN),                                 'hystcomp:nonFiniteInput'
    @() c.step(-Inf),                                'hystcomp:nonFiniteInput'
    @() c.process([yd; NaN]),                        'hystcomp:nonFiniteInput'
    @() hystcomp.compensate(model, 'ihc', [1 Inf]),  'hystcomp:nonFiniteInput'
    @() hystcomp.identify([v; NaN], [yd; 1]),        'hystcomp:nonFiniteInput'
    @() hystcomp.e_mhe(yd, [yd(1:end - 1); NaN]),    'hystcomp:nonFiniteInput'
    @() hystcomp.predict(model, [0 NaN]),            'hystcomp:nonFiniteInput'
    % empty
    @() c.step([]),                                  'hystcomp:wrongSize'
    @() c.process([]),                               'hystcomp:empty'
    @() c.process(zeros(1, 0)),                      'hystcomp:empty'
    @() hystcomp.identify([], []),                   'hystcomp:empty'
    @() hystcomp.compensate(model, 'ihc', []),       'hystcomp:empty'
    @() hystcomp.e_m([], []),                        'hystcomp:empty'
    @() hystcomp.predict(model, []),                 'hystcomp:empty'
    % a matrix instead of a vector (or a scalar)
    @() c.step([40 41]),                             'hystcomp:wrongSize'
    @() c.process(ones(2, 3)),                       'hystcomp:wrongSize'
    @() c.process(ones(2, 2, 2)),                    'hystcomp:wrongSize'
    @() hystcomp.identify(ones(10, 2), ones(10, 2)), 'hystcomp:wrongSize'
    @() hystcomp.e_rms(ones(3), ones(3)),            'hystcomp:wrongSize'
    @() hystcomp.Compensator(model, 'ihc', [0 5 10]), 'hystcomp:wrongSize'
    % lengths
    @() hystcomp.identify(v, yd(1:99)),              'hystcomp:lengthMismatch'
    @() hystcomp.e_m(yd, yd(1:50)),                  'hystcomp:lengthMismatch'
    % too many or too few arguments, and outputs
    @() hystcomp.e_m(yd),                            'hystcomp:nargin'
    @() hystcomp.e_m(yd, yd, 3),                     'hystcomp:nargin'
    @() hystcomp.Compensator(),                      'hystcomp:nargin'
    @() hystcomp.Compensator(model),                 'hystcomp:nargin'
    @() hystcomp.Compensator(model, 'ihc', [], 4),   'hystcomp:nargin'
    @() hystcomp.Compensator(model, 'ihc', [], 'Fast', true), 'hystcomp:unknownOption'
    @() hystcomp.Compensator(model, 'wihc-delayed', [], 'AllowUnstableDelay', 'yes'), 'hystcomp:wrongType'
    @() c.step(),                                    'hystcomp:nargin'
    @() c.step(1, 2),                                'hystcomp:nargin'
    @() c.reset(1),                                  'hystcomp:nargin'
    @() hystcomp.compensate(model, 'ihc'),           'hystcomp:nargin'
    @() hystcomp.load_model(),                       'hystcomp:nargin'
    @() two_outputs(@() hystcomp.e_m(yd, yd + 1)),   'hystcomp:nargout'
    @() two_outputs(@() c.process(yd)),              'hystcomp:nargout'
    @() hystcomp_mex(),                              'hystcomp:unknownCommand'
    @() hystcomp_mex('format_disk'),                 'hystcomp:unknownCommand'
    @() hystcomp_mex(42),                            'hystcomp:unknownCommand'
    % options
    @() hystcomp.identify(v, yd, 'n'),               'hystcomp:invalidOption'
    @() hystcomp.identify(v, yd, 'colour', 1),       'hystcomp:invalidOption'
    @() hystcomp.identify(v, yd, 3, 1),              'hystcomp:invalidOption'
    @() hystcomp.identify(v, yd, 'method', 'best'),  'hystcomp:invalidOption'
    @() hystcomp.identify(v, yd, 'n', 2.5),          'hystcomp:invalidArgument'
    @() hystcomp.identify(v, yd, 'n', -1),           'hystcomp:invalidArgument'
    @() hystcomp.identify(v, yd, 'n', 1e30),         'hystcomp:invalidArgument'
    @() hystcomp.identify(v, yd, 'n', NaN),          'hystcomp:invalidArgument'
    @() hystcomp.identify(v, yd, 'holdout', 1),      'hystcomp:invalidArgument'
    @() hystcomp.e_mhe(yd, yd + 1, 0),               'hystcomp:invalidArgument'
    @() hystcomp.e_mhe(yd, yd + 1, 11),              'hystcomp:invalidArgument'
    % the library's refusals, with its message
    @() hystcomp.identify(v, -yd),                   'hystcomp:identificationFailed'
    @() hystcomp.identify(v(1:5), yd(1:5)),          'hystcomp:invalidArgument'
    @() hystcomp.Compensator(model, 'ihc', [-40 40]), 'hystcomp:notInvertible'
    @() hystcomp.Compensator(inverse, 'ihc'),        'hystcomp:wrongDirection'
    @() hystcomp.compensate(model, 'dihc', yd),      'hystcomp:wrongDirection'
    @() hystcomp.compensate(model, 'best', yd),      'hystcomp:invalidArgument'
    @() hystcomp.Compensator(model, 'ihc', [5 5]),   'hystcomp:invalidArgument'
    @() hystcomp.load_model(fullfile(root, 'no-such-model.json')), 'hystcomp:io'
    @() hystcomp.load_model(broken),                 'hystcomp:invalidModelFile'
    @() hystcomp.save_model(model, fullfile(root, 'no', 'such', 'dir', 'm.json')), 'hystcomp:io'
    @() hystcomp.save_model(struct('direction', 'plant'), broken), 'hystcomp:invalidModel'
    @() hystcomp.e_m(ones(10, 1), (1:10)'),          'hystcomp:invalidArgument'
};
for k = 1:size(cases, 1)
    try
        expect_error(cases{k, 1}, cases{k, 2});
    catch e
        error('test:failed', 'case %d (%s): %s', k, func2str(cases{k, 1}), e.message);
    end
end
% Refused samples leave the compensator as it was.
c.reset();
first = c.step(yd(1));
expect_error(@() c.process([yd(2); NaN]), 'hystcomp:nonFiniteInput');
both = hystcomp.compensate(model, 'ihc', yd(1:2));
check(c.step(yd(2)) == both(2), 'state changed by NaN');
d = c.diagnostics();
check(d.non_finite == 0 && first >= 0, 'non_finite counted');
% The library's message arrives whole.
try
    hystcomp.Compensator(inverse, 'ihc');
catch e
    check(~isempty(strfind(e.message, 'ihc needs a plant model')), 'message: %s', e.message);
end
note = sprintf('%d bad calls, each refused with its identifier', size(cases, 1));
end

function two_outputs(f)
[a, b] = f(); %#ok<ASGLU>
end

function note = freed_and_forged_handles_are_refused(root)
model = hystcomp.load_model(fullfile(root, 'models', 'table1-plant.json'));
before = hystcomp_mex('live_compensators');
c = hystcomp.Compensator(model, 'ihc');
check(hystcomp_mex('live_compensators') == before + 1, 'not counted');
id = hystcomp_mex('compensator_new', model, 'wihc');
check(isa(id, 'uint64') && hystcomp_mex('compensator_step', id, 40) > 0, 'raw id');
check(hystcomp_mex('compensator_free', id), 'free a live id');
% Freed: refused, and freeing again is harmless (a destructor must not fail).
expect_error(@() hystcomp_mex('compensator_step', id, 40), 'hystcomp:invalidHandle');
check(~hystcomp_mex('compensator_free', id), 'freed twice');
% Its slot reused by a new compensator: the old id still refused (generations).
again = hystcomp_mex('compensator_new', model, 'wihc');
expect_error(@() hystcomp_mex('compensator_process', id, [1 2]), 'hystcomp:invalidHandle');
hystcomp_mex('compensator_free', again);
% Forged ids: near misses of a live one, made up, of the wrong class.
live = hystcomp_mex('compensator_new', model, 'ihc');
for forged = {live + 1, live - 1, bitxor(live, bitshift(uint64(1), 40)), ...
              bitxor(live, bitshift(uint64(1), 50)), uint64(0), intmax('uint64')}
    expect_error(@() hystcomp_mex('compensator_step', forged{1}, 40), 'hystcomp:invalidHandle');
end
expect_error(@() hystcomp_mex('compensator_reset', double(live)), 'hystcomp:invalidHandle');
expect_error(@() hystcomp_mex('compensator_diagnostics', [live live]), 'hystcomp:invalidHandle');
expect_error(@() hystcomp_mex('compensator_step', int64(live), 1), 'hystcomp:invalidHandle');
hystcomp_mex('compensator_free', live);
% A deleted object refuses every method (MATLAB itself refuses deleted handles first, with
% MATLAB:class:InvalidHandle; Octave leaves it to the gateway).
delete(c);
deleted = {@() c.step(40), @() c.process([1 2]), @() c.reset(), @() c.diagnostics()};
for k = 1:numel(deleted)
    try
        deleted{k}();
        error('test:failed', 'a deleted compensator answered');
    catch e
        check(any(strcmp(e.identifier, {'hystcomp:invalidHandle', 'MATLAB:class:InvalidHandle'})), ...
              'deleted: %s', e.identifier);
    end
end
delete(c); % twice: nothing happens
% The last reference going frees it.
d = hystcomp.Compensator(model, 'ihc');
check(hystcomp_mex('live_compensators') == before + 1, 'not counted');
clear d
check(hystcomp_mex('live_compensators') == before, 'the last reference went, not the compensator');
note = '';
end

function note = simulink_s_function_steps_the_compensator(root, mexdir, library)
% simulink/sfun_hystcomp.c compiled by mkoctfile against a stand-in simstruc.h and driven step
% by step as Simulink would (Simulink cannot run here): the same drive as the compensator.
if ~exist('OCTAVE_VERSION', 'builtin')
    note = 'SKIPPED: the stand-in simstruc.h is for Octave; in MATLAB build the S-function with mex';
    return;
end
stub = fullfile(root, 'bindings', 'matlab', 'tests', 'simulink_stub');
harness = fullfile(mexdir, ['sfun_harness.' mexext()]);
[out, status] = mkoctfile('--mex', '-Wall', '-Wextra', ['-I' stub], ...
                          ['-I' fullfile(root, 'bindings', 'c', 'include')], ...
                          fullfile(stub, 'sfun_harness.c'), library, '-lpthread', '-ldl', ...
                          '-lm', '-o', harness);
check(status == 0, 'mkoctfile failed: %s', out);
check(isempty(strfind(out, 'warning')), 'the S-function compiles with warnings: %s', out);
plant = fullfile(root, 'models', 'table1-plant.json');
yd = 37.5 + 20 * sin(2 * pi * (0:1e-4:0.5)');
yd(100) = NaN; % a sensor glitch: held, not propagated
for method = {'ihc', 'wihc-guarded'}
    [v, ts] = sfun_harness(plant, method{1}, [0 10], 1e-4, yd);
    c = hystcomp.Compensator(plant, method{1}, [0 10]);
    expected = [c.process(yd(1:99)); NaN; c.process(yd(101:end))];
    expected(100) = expected(99);
    delete(c);
    check(ts == 1e-4, 'sample time %g', ts);
    % The compensator's state skipped the NaN sample, as the S-function's did.
    check(isequal(v, expected), '%s: the S-function differs from the compensator', method{1});
end
try
    sfun_harness(fullfile(root, 'models', 'table2-inverse.json'), 'ihc', [], 1e-4, yd);
    error('test:failed', 'a wrong-direction model was accepted');
catch e
    check(strcmp(e.identifier, 'hystcomp:sfunction') && ...
          ~isempty(strfind(e.message, 'ihc needs a plant model')), 'error: %s', e.message);
end
try
    sfun_harness(plant, 'ihc', [0 10], -1, yd);
    error('test:failed', 'a negative sample time was accepted');
catch e
    check(~isempty(strfind(e.message, 'sample time')), 'error: %s', e.message);
end
note = '';
end
