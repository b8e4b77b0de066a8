function mexfile = build(varargin)
%BUILD Compile the hystcomp MEX gateway (hystcomp_mex) against the C library.
%   First build the C library from the repository's root (a static library, no other
%   dependency):
%     cargo build --release -p hystcomp-c
%   Then, in MATLAB or Octave, from bindings/matlab:
%     build              % hystcomp_mex.<mexext> here, beside +hystcomp
%     addpath(pwd)       % hystcomp.identify, hystcomp.Compensator, ... are then on the path
%
%   build('library', LIB, 'output', DIR) takes the static library LIB instead of
%   ../../target/release/libhystcomp.a and writes the MEX file into DIR instead of this folder
%   (the tests build against the debug library into target/matlab). Returns the MEX file's path.
%
%   What it runs (from bindings/matlab, Linux; paths shortened):
%     Octave:  mkoctfile --mex -Isrc -I../c/include src/*.c LIB -lpthread -ldl -lm
%              -o DIR/hystcomp_mex.mex
%     MATLAB:  mex -R2017b -Isrc -I../c/include src/hystcomp_mex.c src/args.c src/model.c
%              src/handles.c LIB -lpthread -ldl -lm -outdir DIR -output hystcomp_mex
%   On macOS drop -lpthread -ldl; on Windows (MSVC) give target\release\hystcomp.lib and the
%   system libraries Rust's standard library needs: ws2_32.lib userenv.lib bcrypt.lib
%   ntdll.lib advapi32.lib.
here = fileparts(mfilename('fullpath'));
options = struct('library', fullfile(here, '..', '..', 'target', 'release', 'libhystcomp.a'), ...
                 'output', here);
if mod(numel(varargin), 2) ~= 0
    error('hystcomp:invalidOption', 'build takes name, value pairs: ''library'', ''output''');
end
for k = 1:2:numel(varargin)
    name = varargin{k};
    if ~ischar(name) || ~isfield(options, lower(name))
        error('hystcomp:invalidOption', 'build''s options are ''library'' and ''output''');
    end
    options.(lower(name)) = varargin{k + 1};
end
if ~exist(options.library, 'file')
    error('hystcomp:io', ['the C library %s is missing; build it first from the ' ...
          'repository''s root: cargo build --release -p hystcomp-c'], options.library);
end
if ~exist(options.output, 'dir')
    mkdir(options.output);
end
sources = {'hystcomp_mex.c', 'args.c', 'model.c', 'handles.c'};
sources = cellfun(@(s) fullfile(here, 'src', s), sources, 'UniformOutput', false);
includes = {['-I' fullfile(here, 'src')], ['-I' fullfile(here, '..', 'c', 'include')]};
system_libraries = {};
if isunix() && ~ismac()
    system_libraries = {'-lpthread', '-ldl', '-lm'};
end
if exist('OCTAVE_VERSION', 'builtin')
    mexfile = fullfile(options.output, ['hystcomp_mex.' mexext()]);
    [out, status] = mkoctfile('--mex', includes{:}, sources{:}, options.library, ...
                              system_libraries{:}, '-o', mexfile);
    if status ~= 0
        error('hystcomp:build', 'mkoctfile failed:\n%s', out);
    end
else
    mex('-R2017b', includes{:}, sources{:}, options.library, system_libraries{:}, ...
        '-outdir', options.output, '-output', 'hystcomp_mex');
    mexfile = fullfile(options.output, ['hystcomp_mex.' mexext()]);
end
end
