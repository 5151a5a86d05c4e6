// encoder_core: three or four quadrature encoder channels counted in windows (paper section 2.2).
//
// tick_generator (window clock, PERIOD register) -> capture = tick while CONTROL.ENABLE; CHANNELS
// encoder_channel (synchronizer, glitch filter, decoder, window counter, position, error count);
// encoder_regs (register bus, status, window bank and its snapshot). See docs/RTL.md.
// CHANNELS (3 or 4, default the register map's 4) is how many wheels the robot has: the ports and
// the register map stay 4 wide, a channel at or above CHANNELS is not built (its pins ignored, its
// counts, positions, direction and errors 0), and CONFIG.CHANNELS tells the host.
//
// Window outputs for the streamer: win_valid_o pulses for one cycle after each capture; win_seq_o,
// win_timestamp_o, win_count_o (4 x signed 32, channel 0 in the low bits), win_position_o,
// win_dir_o and status_o (STATUS as it stood at the capture) then hold until the next capture.
// win_consumed_i (one-cycle strobe) marks the window as taken, for STATUS.OVERRUN.
// The gyro's window (gyro_*_i) comes from outside (omniloc_top's gyro_ctrl, ticked by tick_o) and
// goes into the window bank with the counts; tied to 0 where there is no gyro.
//
// Assumptions: enc_a_i/enc_b_i asynchronous; a single clock; rst_i synchronous, active high,
// and held for at least one cycle. CLK_HZ / TICK_HZ >= PERIOD_MIN_CYCLES. Defaults: the paper's
// 40 MHz and 100 Hz (common/regmap.json "link"); widths from the generated map.
`resetall
`timescale 1ns / 1ps
`default_nettype none

`include "omniloc_regs.vh"

module encoder_core #(
    parameter integer CLK_HZ = `OMNILOC_PAPER_CLOCK_HZ,
    parameter integer TICK_HZ = `OMNILOC_TICK_HZ,
    parameter integer CHANNELS = `OMNILOC_CHANNELS,
    parameter integer BANK_IDX_W = $clog2(`OMNILOC_BODY_WINDOW_BYTES + 1)
) (
    input  wire                                         clk_i,
    input  wire                                         rst_i,
    input  wire [`OMNILOC_CHANNELS-1:0]                 enc_a_i,
    input  wire [`OMNILOC_CHANNELS-1:0]                 enc_b_i,
    // the gyro's window (gyro_accum ticked by tick_o), held from the cycle after the tick
    input  wire signed [`OMNILOC_GYRO_SUM_BITS-1:0]     gyro_sum_i,
    input  wire [`OMNILOC_GYRO_COUNT_BITS-1:0]          gyro_count_i,
    input  wire [`OMNILOC_BODY_WINDOW_GYRO_FLAGS_W-1:0] gyro_flags_i,
    // register bus
    input  wire [`OMNILOC_ADDR_W-1:0]                   reg_addr_i,
    input  wire                                         reg_rd_i,
    input  wire                                         reg_wr_i,
    input  wire [`OMNILOC_DATA_W-1:0]                   reg_wdata_i,
    output wire [`OMNILOC_DATA_W-1:0]                   reg_rdata_o,
    output wire                                         reg_ack_o,
    output wire                                         reg_err_o,
    // windows for streaming
    output wire                                         win_valid_o,
    output wire [`OMNILOC_DATA_W-1:0]                   win_seq_o,
    output wire [`OMNILOC_DATA_W-1:0]                   win_timestamp_o,
    output wire [`OMNILOC_CHANNELS*`OMNILOC_DATA_W-1:0] win_count_o,
    output wire [`OMNILOC_CHANNELS*`OMNILOC_DATA_W-1:0] win_position_o,
    output wire [`OMNILOC_CHANNELS-1:0]                 win_dir_o,
    output wire [`OMNILOC_BODY_WINDOW_STATUS_W-1:0]     status_o,
    input  wire         win_consumed_i,
    output wire         stream_en_o,
    output wire         tick_o,
    // the frozen window bank, byte k of the WINDOW body layout (TELEMETRY / SNAPSHOT_RESP)
    input  wire [BANK_IDX_W-1:0] bank_idx_i,
    output wire [7:0]            bank_byte_o
);

localparam integer DATA_W = `OMNILOC_DATA_W;
localparam integer CH = `OMNILOC_CHANNELS;
localparam integer ERR_W = `OMNILOC_ERROR_COUNT_BITS;

wire                                    enable;
wire [`OMNILOC_CONTROL_DECODE_W-1:0]    decode;
wire [`OMNILOC_FILTER_LENGTH_W-1:0]     filter_len;
wire [`OMNILOC_PERIOD_CYCLES_W-1:0]     period;
wire [DATA_W-1:0]                       timestamp;
wire                                    tick;
wire [CH-1:0]                           illegal;
wire [CH*ERR_W-1:0]                     err_count;
wire        capture = tick & enable;

assign tick_o = tick;

tick_generator #(.CLK_HZ(CLK_HZ), .TICK_HZ(TICK_HZ)) u_tick (
    .clk_i(clk_i), .rst_i(rst_i), .period_i(period), .tick_o(tick),
    /* verilator lint_off PINCONNECTEMPTY */
    .period_o(),
    /* verilator lint_on PINCONNECTEMPTY */
    .timestamp_o(timestamp)
);

genvar ch;
generate
    // Elaboration stops here, naming the rule, when CHANNELS is not 3 or 4 (no such module).
    if (CHANNELS < 3 || CHANNELS > CH) begin : g_bad_channels
        encoder_core_CHANNELS_must_be_3_or_4 u_stop ();
    end
    for (ch = 0; ch < CH; ch = ch + 1) begin : g_ch
        if (ch >= CHANNELS) begin : g_off
            // A wheel the robot does not have: nothing built, nothing counted.
            /* verilator lint_off UNUSEDSIGNAL */
            wire unused_pins = enc_a_i[ch] ^ enc_b_i[ch];
            /* verilator lint_on UNUSEDSIGNAL */
            assign win_count_o[DATA_W*ch +: DATA_W] = {DATA_W{1'b0}};
            assign win_position_o[DATA_W*ch +: DATA_W] = {DATA_W{1'b0}};
            assign win_dir_o[ch] = 1'b0;
            assign illegal[ch] = 1'b0;
            assign err_count[ERR_W*ch +: ERR_W] = {ERR_W{1'b0}};
        end else begin : g_on
            encoder_channel u_ch (
                .clk_i(clk_i), .rst_i(rst_i), .a_i(enc_a_i[ch]), .b_i(enc_b_i[ch]),
                .filter_len_i(filter_len), .en_i(enable), .mode_i(decode), .capture_i(capture),
                .win_count_o(win_count_o[DATA_W*ch +: DATA_W]), .win_position_o(win_position_o[DATA_W*ch +: DATA_W]),
                .win_dir_o(win_dir_o[ch]),
                /* verilator lint_off PINCONNECTEMPTY */
                .position_o(), .dir_o(),
                /* verilator lint_on PINCONNECTEMPTY */
                .err_o(illegal[ch]), .err_count_o(err_count[ERR_W*ch +: ERR_W])
            );
        end
    end
endgenerate

encoder_regs #(.CLK_HZ(CLK_HZ), .TICK_HZ(TICK_HZ), .CHANNELS(CHANNELS)) u_regs (
    .clk_i(clk_i), .rst_i(rst_i),
    .reg_addr_i(reg_addr_i), .reg_rd_i(reg_rd_i), .reg_wr_i(reg_wr_i), .reg_wdata_i(reg_wdata_i),
    .reg_rdata_o(reg_rdata_o), .reg_ack_o(reg_ack_o), .reg_err_o(reg_err_o),
    .enable_o(enable), .decode_o(decode), .stream_o(stream_en_o), .filter_len_o(filter_len),
    .period_o(period),
    .capture_i(capture), .illegal_i(illegal), .win_consumed_i(win_consumed_i),
    .timestamp_i(timestamp), .win_count_i(win_count_o), .win_position_i(win_position_o),
    .win_dir_i(win_dir_o), .err_count_i(err_count),
    .gyro_sum_i(gyro_sum_i), .gyro_count_i(gyro_count_i), .gyro_flags_i(gyro_flags_i),
    .win_valid_o(win_valid_o), .win_seq_o(win_seq_o), .win_timestamp_o(win_timestamp_o),
    .win_status_o(status_o), .bank_idx_i(bank_idx_i), .bank_byte_o(bank_byte_o),
    /* verilator lint_off PINCONNECTEMPTY */
    .status_o()
    /* verilator lint_on PINCONNECTEMPTY */
);

endmodule

`resetall
