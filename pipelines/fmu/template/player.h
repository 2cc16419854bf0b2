/* Generic load-history player shared by the FMI 2.0 and FMI 3.0 wrappers.
 *
 * The history table lives in the FMU's resources folder (see player.c for the
 * binary layout), so one compiled binary plays any exported history and the
 * FMU size grows only with the data.
 *
 * Playback: the output at simulation time t is the history at
 *     tau = t - time_offset                                  (s)
 * linearly interpolated between samples. Outside the sampled range the first
 * or last sample is held, unless `periodic` is set: then tau is wrapped into
 * [t_first, t_first + period); if period exceeds the sampled span, the gap
 * after the last sample is bridged linearly back to the first sample.
 */
#ifndef FRETWORK_PLAYER_H
#define FRETWORK_PLAYER_H

#include <stddef.h>

/* Value references, fixed for every exported FMU (mirrored in pipelines/fmu.py). */
#define PLAYER_VR_TIME 0
#define PLAYER_VR_TIME_OFFSET 1
#define PLAYER_VR_PERIOD 2
#define PLAYER_VR_PERIODIC 3
#define PLAYER_VR_FIRST_OUTPUT 100

#define PLAYER_TABLE_FILE "histories.bin"
#define PLAYER_TOKEN_SIZE 64

typedef struct {
    size_t n_samples;
    size_t n_signals;
    double *time;     /* (n_samples,) strictly increasing, s */
    double *values;   /* (n_samples, n_signals) row-major, signal units */
    double *outputs;  /* (n_signals,) values at the current time */
    size_t hint;      /* last interval used: playback mostly moves forward */

    double current_time;  /* simulation time, s */
    double time_offset;   /* s */
    double period;        /* s */
    int periodic;
    int outputs_valid;
} Player;

/* Read the table in `resource_dir` and check it belongs to `token`.
 * Returns 0 on success; otherwise writes a reason into `message`. */
int player_load(Player *player, const char *resource_dir, const char *token,
                char *message, size_t message_size);

void player_free(Player *player);

/* Check parameter values before playback starts; 0 if valid. */
int player_check_parameters(const Player *player, char *message, size_t message_size);

/* Values of all signals at the current time (cached until time or a parameter changes). */
const double *player_outputs(Player *player);

/* Turn an FMI 2.0 resource location URI into a local directory path (percent-decoded).
 * Returns 0 on success. */
int player_uri_to_path(const char *uri, char *path, size_t path_size);

#endif
