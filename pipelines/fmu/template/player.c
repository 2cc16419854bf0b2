/* History table loading and linear-interpolation playback (see player.h).
 *
 * Binary layout of resources/histories.bin, little-endian, written by
 * pipelines/fmu.py:
 *   offset  0  char[8]   magic "FRETHIS1"
 *   offset  8  uint32    byte-order mark 0x01020304
 *   offset 12  uint32    reserved, 0
 *   offset 16  uint64    n_samples (>= 2)
 *   offset 24  uint64    n_signals
 *   offset 32  char[64]  instantiation token / GUID, NUL padded
 *   offset 96  float64[n_samples]             time, s
 *              float64[n_samples * n_signals] values, row-major (sample, signal)
 */
#include "player.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char MAGIC[8] = {'F', 'R', 'E', 'T', 'H', 'I', 'S', '1'};

static int fail(char *message, size_t message_size, const char *text, const char *detail) {
    snprintf(message, message_size, "%s%s", text, detail ? detail : "");
    return 1;
}

static int read_exact(FILE *file, void *buffer, size_t item_size, size_t count) {
    return fread(buffer, item_size, count, file) == count;
}

int player_load(Player *player, const char *resource_dir, const char *token,
                char *message, size_t message_size) {
    char path[4096];
    char magic[8];
    uint32_t byte_order, reserved;
    uint64_t n_samples, n_signals;
    char stored_token[PLAYER_TOKEN_SIZE + 1];
    FILE *file;
    size_t k;

    memset(player, 0, sizeof(*player));
    if (!resource_dir || !resource_dir[0]) {
        return fail(message, message_size, "no resource location given; the history table cannot be found", NULL);
    }
    {
        size_t length = strlen(resource_dir);
        const char *separator = (resource_dir[length - 1] == '/' || resource_dir[length - 1] == '\\') ? "" : "/";
        if ((size_t)snprintf(path, sizeof(path), "%s%s%s", resource_dir, separator, PLAYER_TABLE_FILE) >= sizeof(path)) {
            return fail(message, message_size, "resource path too long: ", resource_dir);
        }
    }
    file = fopen(path, "rb");
    if (!file) {
        return fail(message, message_size, "cannot open history table ", path);
    }
    memset(stored_token, 0, sizeof(stored_token));
    if (!read_exact(file, magic, 1, 8) || !read_exact(file, &byte_order, 4, 1) ||
        !read_exact(file, &reserved, 4, 1) || !read_exact(file, &n_samples, 8, 1) ||
        !read_exact(file, &n_signals, 8, 1) || !read_exact(file, stored_token, 1, PLAYER_TOKEN_SIZE)) {
        fclose(file);
        return fail(message, message_size, "history table header is truncated: ", path);
    }
    if (memcmp(magic, MAGIC, 8) != 0 || byte_order != 0x01020304u) {
        fclose(file);
        return fail(message, message_size, "not a fretwork history table (or wrong byte order): ", path);
    }
    if (token && strcmp(token, stored_token) != 0) {
        fclose(file);
        return fail(message, message_size,
                    "history table does not belong to this modelDescription.xml (token mismatch): ", path);
    }
    if (n_samples < 2) {
        fclose(file);
        return fail(message, message_size, "history table needs at least two samples: ", path);
    }
    player->n_samples = (size_t)n_samples;
    player->n_signals = (size_t)n_signals;
    player->time = (double *)malloc(player->n_samples * sizeof(double));
    player->values = (double *)malloc(player->n_samples * (player->n_signals ? player->n_signals : 1) * sizeof(double));
    player->outputs = (double *)calloc(player->n_signals ? player->n_signals : 1, sizeof(double));
    if (!player->time || !player->values || !player->outputs) {
        fclose(file);
        player_free(player);
        return fail(message, message_size, "out of memory loading ", path);
    }
    if (!read_exact(file, player->time, sizeof(double), player->n_samples) ||
        !read_exact(file, player->values, sizeof(double), player->n_samples * player->n_signals)) {
        fclose(file);
        player_free(player);
        return fail(message, message_size, "history table data is truncated: ", path);
    }
    fclose(file);
    for (k = 1; k < player->n_samples; k++) {
        if (!(player->time[k] > player->time[k - 1])) {
            player_free(player);
            return fail(message, message_size, "history time is not strictly increasing in ", path);
        }
    }
    player->period = player->time[player->n_samples - 1] - player->time[0];
    return 0;
}

void player_free(Player *player) {
    free(player->time);
    free(player->values);
    free(player->outputs);
    player->time = player->values = player->outputs = NULL;
}

int player_check_parameters(const Player *player, char *message, size_t message_size) {
    double span = player->time[player->n_samples - 1] - player->time[0];
    if (!isfinite(player->time_offset)) {
        return fail(message, message_size, "time_offset must be a finite number of seconds", NULL);
    }
    if (player->periodic && !(player->period >= span && isfinite(player->period))) {
        char detail[64];
        snprintf(detail, sizeof(detail), "%.17g s", span);
        return fail(message, message_size, "period must be finite and at least the history span of ", detail);
    }
    return 0;
}

/* Index k with time[k] <= tau < time[k+1], for time[0] <= tau < time[n-1]. */
static size_t find_interval(Player *player, double tau) {
    const double *time = player->time;
    size_t low, high, k = player->hint;
    if (time[k] <= tau && tau < time[k + 1]) {
        return k;
    }
    if (k + 2 < player->n_samples && time[k + 1] <= tau && tau < time[k + 2]) {
        player->hint = k + 1;
        return k + 1;
    }
    low = 0;
    high = player->n_samples - 1;
    while (high - low > 1) {
        size_t middle = low + (high - low) / 2;
        if (time[middle] <= tau) {
            low = middle;
        } else {
            high = middle;
        }
    }
    player->hint = low;
    return low;
}

static void blend(const double *row_a, const double *row_b, double weight, size_t n, double *out) {
    size_t j;
    for (j = 0; j < n; j++) {
        out[j] = row_a[j] + weight * (row_b[j] - row_a[j]);
    }
}

const double *player_outputs(Player *player) {
    const size_t n = player->n_samples, m = player->n_signals;
    const double t_first = player->time[0], t_last = player->time[n - 1];
    const double *first_row = player->values, *last_row = player->values + (n - 1) * m;
    double tau;

    if (player->outputs_valid) {
        return player->outputs;
    }
    tau = player->current_time - player->time_offset;
    /* Wrap only outside the first period so sample times in it are hit exactly. */
    if (player->periodic && player->period > 0.0 && (tau < t_first || tau >= t_first + player->period)) {
        double phase = fmod(tau - t_first, player->period);
        if (phase < 0.0) {
            phase += player->period;
        }
        tau = t_first + phase;
    }
    if (tau <= t_first) {
        memcpy(player->outputs, first_row, m * sizeof(double));
    } else if (tau >= t_last) {
        double gap = t_first + player->period - t_last;
        if (player->periodic && gap > 0.0 && tau > t_last) {
            blend(last_row, first_row, (tau - t_last) / gap, m, player->outputs);
        } else {
            memcpy(player->outputs, last_row, m * sizeof(double));
        }
    } else {
        size_t k = find_interval(player, tau);
        double weight = (tau - player->time[k]) / (player->time[k + 1] - player->time[k]);
        blend(player->values + k * m, player->values + (k + 1) * m, weight, m, player->outputs);
    }
    player->outputs_valid = 1;
    return player->outputs;
}

static int hex_value(char c) {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

int player_uri_to_path(const char *uri, char *path, size_t path_size) {
    const char *source = uri;
    size_t length = 0;
    if (!uri) {
        return 1;
    }
    if (strncmp(source, "file://", 7) == 0) {
        source += 7;
        /* file://host/path: only the local host is reachable */
        if (strncmp(source, "localhost/", 10) == 0) {
            source += 9;
        }
    } else if (strncmp(source, "file:", 5) == 0) {
        source += 5;
    }
#ifdef _WIN32
    /* file:///C:/dir -> C:/dir */
    if (source[0] == '/' && source[1] && source[2] == ':') {
        source += 1;
    }
#endif
    while (*source) {
        char c = *source;
        if (c == '%' && hex_value(source[1]) >= 0 && hex_value(source[2]) >= 0) {
            c = (char)(hex_value(source[1]) * 16 + hex_value(source[2]));
            source += 2;
        }
        if (length + 1 >= path_size) {
            return 1;
        }
        path[length++] = c;
        source++;
    }
    path[length] = '\0';
    return 0;
}
